!> The thesis's single element reduced to a material point in uniaxial stress: the axial
!> strain (or stress) history is imposed and the lateral stresses are driven to zero by Newton's
!> method on the consistent tangent of the implicit stress update. Time stepping with initial,
!> minimum and maximum increments and automatic cut-back, like the original APDL deck.
module usharp_umat_driver
   use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
   use usharp_kinds, only: dp
   use usharp_error, only: error_type, fatal_error, stat_failure
   use usharp_strings, only: real_str
   use usharp_model, only: model_type, update_status_ok
   use usharp_history, only: history_type, control_strain
   use usharp_simulation, only: solver_options, sim_result
   use usharp_lapack, only: solve_dense
   implicit none
   private

   public :: simulate_umat

   integer, parameter :: max_equilibrium = 25

contains

   !> Simulate the history from the virgin state with the implicit stress update, writing the
   !> response at the output times tout (s). Increments end exactly at corners and outputs.
   subroutine simulate_umat(model, hist, tout, opts, res, error)
      class(model_type), intent(in) :: model
      type(history_type), intent(in) :: hist
      real(dp), intent(in) :: tout(:)
      type(solver_options), intent(in) :: opts
      type(sim_result), intent(out) :: res
      type(error_type), allocatable, intent(out) :: error
      real(dp) :: t, dt, h, tstop, eps(6), y(model%n_state()), eps_new(6), y_new(model%n_state())
      real(dp) :: sig(6)
      real(dp) :: tend, tol
      integer :: iout, kc, nit, nsub
      logical :: ok

      call res%allocate(size(tout))
      t = hist%t(1)
      tend = hist%end_time()
      tol = 1.0e-12_dp*max(1.0_dp, abs(tend))
      ! A history that starts away from 0 (a measured strain at 3e-5) starts there
      ! elastically, in uniaxial stress, as the other integrators do
      eps = 0.0_dp
      call model%state_initial(y)
      sig = 0.0_dp
      if (hist%control == control_strain) then
         eps(1) = hist%v(1)
         sig(1) = model%youngs*eps(1)
      else
         sig(1) = hist%v(1)
         eps(1) = sig(1)/model%youngs
      end if
      eps(2:3) = -model%poisson*eps(1)
      dt = opts%dt_init
      iout = 1
      kc = 2
      call store_outputs()
      do while (t < tend - tol)
         ! Next stop: the next corner or output time after t
         do while (kc < size(hist%t))
            if (hist%t(kc) > t + tol) exit
            kc = kc + 1
         end do
         tstop = hist%t(kc)
         if (iout <= size(tout)) tstop = min(tstop, tout(iout))
         h = min(dt, tstop - t)
         ! Do not leave a sliver before the stop
         if (tstop - (t + h) < 1.0e-3_dp*h) h = tstop - t
         call increment(t, h, eps, y, eps_new, y_new, sig, ok, nit, nsub)
         res%nrhs = res%nrhs + nit
         if (.not. ok) then
            dt = 0.25_dp*h
            if (dt < opts%dt_min) then
               call fatal_error(error, 'umat integration failed at t = '//real_str(t, 'es12.5')// &
                  ' s: the increment fell below dt_min = '//real_str(opts%dt_min, 'es9.2')//' s', &
                  stat_failure)
               return
            end if
            cycle
         end if
         res%nsteps = res%nsteps + 1
         t = t + h
         if (abs(t - tstop) <= tol) t = tstop
         eps = eps_new
         y = y_new
         ! Grow the increment after an easy one
         if (nsub == model%update_substeps() .and. nit <= 4) then
            dt = min(2.0_dp*h, opts%dt_max)
         else
            dt = min(h, opts%dt_max)
         end if
         call store_outputs()
      end do

   contains

      subroutine store_outputs()
         do while (iout <= size(tout))
            if (tout(iout) > t + tol) exit
            res%t(iout) = tout(iout)
            res%strain(iout) = eps(1)
            res%stress(iout) = sig(1)
            call model%state_outputs(y, res%eps_in(iout), res%back(iout), res%drag(iout))
            iout = iout + 1
         end do
      end subroutine store_outputs

      !> One increment from t to t + h: Newton on the free normal strains so that the lateral
      !> stresses vanish (and, under stress control, the axial stress meets the history)
      subroutine increment(t, h, eps0, y0, eps1, y1, sig1, ok, nit, nsub)
         real(dp), intent(in) :: t, h, eps0(6), y0(:)
         real(dp), intent(out) :: eps1(6), y1(:), sig1(6)
         logical, intent(out) :: ok
         integer, intent(out) :: nit, nsub
         real(dp) :: ddsde(6, 6), target(3), load, rhs(3, 1), a(3, 3), stol
         integer :: status, first, it, info
         load = hist%value_at(t + h)
         eps1 = eps0
         if (hist%control == control_strain) then
            first = 2
            target = 0.0_dp
            ! Elastic predictor for the lateral strains
            eps1(1) = load
            eps1(2:3) = eps0(2:3) - model%poisson*(load - eps0(1))
         else
            first = 1
            target = [load, 0.0_dp, 0.0_dp]
         end if
         stol = 1.0e-10_dp*model%youngs
         ok = .false.
         nit = 0
         nsub = 1
         do it = 1, max_equilibrium
            call model%stress_update(eps0, eps1 - eps0, h, y0, sig1, y1, ddsde, status, nsub)
            nit = nit + 1
            if (status /= update_status_ok) return
            rhs(first:3, 1) = target(first:3) - sig1(first:3)
            if (maxval(abs(rhs(first:3, 1))) <= stol) then
               ok = .true.
               return
            end if
            a(first:3, first:3) = ddsde(first:3, first:3)
            call solve_dense(a(first:3, first:3), rhs(first:3, :), info)
            if (info /= 0 .or. .not. all(ieee_is_finite(rhs(first:3, 1)))) return
            eps1(first:3) = eps1(first:3) + rhs(first:3, 1)
         end do
      end subroutine increment
   end subroutine simulate_umat
end module usharp_umat_driver
