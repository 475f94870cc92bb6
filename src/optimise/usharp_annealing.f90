!> Simulated annealing for continuous variables after Corana, Marchesi, Martini and Ridella
!> (1987, ACM TOMS 13): coordinate-wise random moves within a step vector, Metropolis
!> acceptance, the step of each coordinate adjusted after ns cycles towards an acceptance ratio
!> of 0.4-0.6 (c = 2), the temperature lowered by rt after nt adjustments and the search
!> restarted from the best point. Stops when the best objective changed by no more than
!> ftol (relative) over the last four temperatures, or after max_evals evaluations.
module usharp_annealing
   use usharp_kinds, only: dp
   use usharp_math, only: exp_dp
   use usharp_error, only: error_type
   use usharp_optimiser, only: reason_max_evals, objective_type, optimum_type
   use usharp_rng, only: rng_type
   implicit none
   private

   public :: anneal

   integer, parameter :: ns = 20, nt = 5, neps = 4
   real(dp), parameter :: c_step = 2.0_dp

contains

   !> t0: initial temperature (0: the objective at x0); rt: temperature factor; seed: rng
   subroutine anneal(obj, x0, lo, hi, t0, rt, seed, ftol, max_evals, opt, error)
      class(objective_type), intent(inout) :: obj
      real(dp), intent(in) :: x0(:), lo(:), hi(:), t0, rt, ftol
      integer, intent(in) :: seed, max_evals
      type(optimum_type), intent(out) :: opt
      type(error_type), allocatable, intent(out) :: error
      type(rng_type) :: rng
      real(dp) :: x(size(x0)), xp(size(x0)), v(size(x0)), xopt(size(x0)), f, fp, fopt, t, ratio
      real(dp) :: fstar(neps)
      integer :: nacc(size(x0)), n, h, i, j, m, nevals, ntemp
      n = size(x0)
      call rng%seed(seed)
      x = min(max(x0, lo), hi)
      v = 0.5_dp*(hi - lo)
      nevals = 0
      call evaluate(x, f)
      if (allocated(error)) return
      xopt = x
      fopt = f
      t = t0
      if (t <= 0.0_dp) t = max(abs(f), tiny(1.0_dp))
      fstar = huge(1.0_dp)
      ntemp = 0
      opt%reason = reason_max_evals
      outer: do
         nacc = 0
         do m = 1, nt
            do j = 1, ns
               do h = 1, n
                  if (nevals >= max_evals) exit outer
                  xp = x
                  xp(h) = x(h) + (2.0_dp*rng%uniform() - 1.0_dp)*v(h)
                  if (xp(h) < lo(h) .or. xp(h) > hi(h)) xp(h) = lo(h) + rng%uniform()*(hi(h) - lo(h))
                  call evaluate(xp, fp)
                  if (allocated(error)) return
                  if (fp <= f .or. rng%uniform() < exp_dp(-(fp - f)/t)) then
                     x = xp
                     f = fp
                     nacc(h) = nacc(h) + 1
                     if (f < fopt) then
                        xopt = x
                        fopt = f
                     end if
                  end if
               end do
            end do
            do i = 1, n
               ratio = real(nacc(i), dp)/real(ns, dp)
               if (ratio > 0.6_dp) then
                  v(i) = v(i)*(1.0_dp + c_step*(ratio - 0.6_dp)/0.4_dp)
               else if (ratio < 0.4_dp) then
                  v(i) = v(i)/(1.0_dp + c_step*(0.4_dp - ratio)/0.4_dp)
               end if
               v(i) = min(v(i), hi(i) - lo(i))
            end do
            nacc = 0
         end do
         ntemp = ntemp + 1
         fstar = [f, fstar(:neps - 1)]
         if (ntemp >= neps .and. all(abs(fstar - fopt) <= ftol*abs(fopt))) then
            opt%reason = 'best objective steady over four temperatures'
            exit outer
         end if
         t = rt*t
         x = xopt
         f = fopt
      end do outer
      opt%x = xopt
      opt%f = fopt
      opt%nevals = nevals
      opt%iterations = ntemp

   contains

      subroutine evaluate(xe, fe)
         real(dp), intent(in) :: xe(:)
         real(dp), intent(out) :: fe
         nevals = nevals + 1
         call obj%eval(xe, fe, error)
      end subroutine evaluate
   end subroutine anneal
end module usharp_annealing
