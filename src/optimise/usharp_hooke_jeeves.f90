!> Hooke-Jeeves direct search (Hooke and Jeeves 1961; Kaupe's Algorithm 178), with the logic
!> of the original program: relative initial steps, exploratory moves, pattern moves, and a
!> step reduction by rho when an iteration brings no improvement.
module usharp_hooke_jeeves
   use usharp_kinds, only: dp
   use usharp_error, only: error_type
   use usharp_optimiser, only: reason_itermax, reason_max_evals, objective_type, optimum_type
   implicit none
   private

   public :: hooke_jeeves

contains

   !> Minimise obj from x0. rho in (0,1): initial relative step and reduction factor;
   !> stop when the step length <= eps, after itermax iterations or max_evals evaluations.
   subroutine hooke_jeeves(obj, x0, rho, eps, itermax, max_evals, opt, error)
      class(objective_type), intent(inout) :: obj
      real(dp), intent(in) :: x0(:)
      real(dp), intent(in) :: rho, eps
      integer, intent(in) :: itermax, max_evals
      type(optimum_type), intent(out) :: opt
      type(error_type), allocatable, intent(out) :: error
      real(dp) :: xbefore(size(x0)), newx(size(x0)), delta(size(x0)), tmp
      real(dp) :: fbefore, newf, steplength
      integer :: i, iters, nevals
      logical :: keep

      nevals = 0
      newx = x0
      xbefore = x0
      delta = abs(x0*rho)
      where (delta == 0.0_dp) delta = rho
      steplength = rho
      iters = 0
      call evaluate(xbefore, fbefore)
      if (allocated(error)) return
      newf = fbefore
      opt%reason = 'step length <= eps'
      do while (iters < itermax .and. steplength > eps)
         if (nevals >= max_evals) exit
         iters = iters + 1
         newx = xbefore
         call best_nearby(newx, fbefore, newf)
         if (allocated(error)) exit
         ! While the exploration improves, keep making pattern moves
         keep = .true.
         do while (newf < fbefore .and. keep)
            ! max_evals is a budget: none past it (a pattern run could overshoot it by 80 %)
            if (nevals >= max_evals) then
               fbefore = newf
               xbefore = newx
               exit
            end if
            do i = 1, size(x0)
               ! Point the step in the direction that worked
               if (newx(i) <= xbefore(i)) then
                  delta(i) = -abs(delta(i))
               else
                  delta(i) = abs(delta(i))
               end if
               tmp = xbefore(i)
               xbefore(i) = newx(i)
               newx(i) = newx(i) + newx(i) - tmp
            end do
            fbefore = newf
            call best_nearby(newx, fbefore, newf)
            if (allocated(error)) exit
            if (newf >= fbefore) exit
            ! Stop the pattern when no coordinate moved by more than half its step
            keep = .false.
            do i = 1, size(x0)
               if (abs(newx(i) - xbefore(i)) > 0.5_dp*abs(delta(i))) then
                  keep = .true.
                  exit
               end if
            end do
         end do
         if (allocated(error)) exit
         if (steplength >= eps .and. newf >= fbefore) then
            steplength = steplength*rho
            delta = delta*rho
         end if
      end do
      if (iters >= itermax .and. steplength > eps) opt%reason = reason_itermax
      if (nevals >= max_evals .and. steplength > eps) opt%reason = reason_max_evals
      opt%x = xbefore
      opt%f = fbefore
      opt%nevals = nevals
      opt%iterations = iters

   contains

      subroutine evaluate(x, f)
         real(dp), intent(in) :: x(:)
         real(dp), intent(out) :: f
         nevals = nevals + 1
         call obj%eval(x, f, error)
      end subroutine evaluate

      !> Exploratory search around point: each coordinate +delta, else -delta, keep the better
      subroutine best_nearby(point, prevbest, minf)
         real(dp), intent(inout) :: point(:)
         real(dp), intent(in) :: prevbest
         real(dp), intent(out) :: minf
         real(dp) :: z(size(point)), ftmp
         integer :: j, attempt
         logical :: improved
         z = point
         minf = prevbest
         do j = 1, size(point)
            ! Try +delta; if that is no better, flip the step and try again; else restore
            improved = .false.
            do attempt = 1, 2
               if (nevals >= max_evals) exit
               if (attempt == 2) delta(j) = -delta(j)
               z(j) = point(j) + delta(j)
               call evaluate(z, ftmp)
               if (allocated(error)) return
               if (ftmp < minf) then
                  minf = ftmp
                  improved = .true.
                  exit
               end if
            end do
            if (.not. improved) z(j) = point(j)
         end do
         point = z
      end subroutine best_nearby
   end subroutine hooke_jeeves
end module usharp_hooke_jeeves
