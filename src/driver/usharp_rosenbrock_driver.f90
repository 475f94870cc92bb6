!> Uniaxial simulation of a model (usharp_model) with a one-step linearly implicit method: the
!> Rosenbrock method RODAS4 of Hairer and Wanner (order 4 with an embedded order-3 error
!> estimate, L-stable, stiffly accurate; the model's analytic Jacobian, one LU per step). A one-step
!> method starts at full order after every corner of the load history, where CVODE's BDF
!> restarts at order 1; it stops exactly at each corner, so no step straddles a kink.
!> Output between steps: cubic Hermite interpolation of the state and its rates.
!> With effects it integrates the extended model of usharp_effects (the model's states, p
!> and R2; its analytic Jacobian), as CVODE does, but carries p and R2 only where an effect
!> acts through them: elsewhere the model's own states, as without effects.
module usharp_rosenbrock_driver
   use, intrinsic :: ieee_arithmetic, only: ieee_is_finite, ieee_value, ieee_quiet_nan
   use, intrinsic :: iso_fortran_env, only: int64
   use usharp_kinds, only: dp
   use usharp_math, only: spline_power_form, power_piece
   use usharp_error, only: error_type, fatal_error, stat_failure
   use usharp_strings, only: str, real_str
   use usharp_model, only: model_type
   use usharp_effects, only: test_effects, extended_rates, lagged_value, lag_corners, &
                             extended_size, extended_initial, states_act
   use usharp_history, only: history_type, control_strain, segment_type, knot_piece
   use usharp_simulation, only: solver_options, sim_result, check_output_times, rodas4_smooth_rtol
   implicit none
   private

   public :: simulate_rosenbrock, rates, rates_jacobian, rate_system, plain_system

   !> Stages of RODAS4
   integer, parameter :: ns = 6

   !> What the rates see: the model, the current segment of the load (k its index) and, for
   !> the extended model, the effects, the stiffness E/(1 + kappa) seen through the
   !> compliance and the control's corners with their lagged values
   type :: rate_system
      class(model_type), allocatable :: model
      !> The states that must stay positive (the model's positive_states)
      integer, allocatable :: positive(:)
      type(segment_type) :: seg
      integer :: k = 1
      !> A smooth forcing through the samples (tc, vc) and the last sample kend of the branch
      !> that begins at sample k; the spline is searched between samples lo and hi when
      !> hi > 0 (the span of the current step), else over the branch. Its pieces in power
      !> form (spline_power_form), evaluated at every stage; seen through a lag (extended
      !> model), its second derivatives at the samples instead
      logical :: smooth = .false.
      integer :: kend = 1, lo = 0, hi = 0
      real(dp), allocatable :: mc(:)
      real(dp), allocatable :: pc(:, :)
      logical :: extended = .false.
      !> States carried beyond the model's own: the extended model's p and R2 (2), or none
      !> where no effect acts through them
      integer :: extra = 0
      type(test_effects) :: eff
      real(dp) :: stiffness = 0.0_dp
      real(dp), allocatable :: tc(:), vc(:), yk(:)
      !> Non-isothermal: the history's corner times (s) and temperatures there (K)
      real(dp), allocatable :: tt(:), temp(:)
   end type rate_system

   !> RODAS4 (Hairer and Wanner 1996, Sec. IV.7) in the form G K_i = f(t + alpha_i h,
   !> y + sum_j a_ij K_j) + sum_j c_ij K_j / h + gamma_i h df/dt with G = I/(gamma h) - J;
   !> the step is y + sum_j m_j K_j and K_6 is the error estimate
   real(dp), parameter :: gam = 0.25_dp
   real(dp), parameter :: alpha(ns) = [0.0_dp, 0.386_dp, 0.21_dp, 0.63_dp, 1.0_dp, 1.0_dp]
   real(dp), parameter :: gamma_i(ns) = [0.25_dp, -0.1043_dp, 0.1035_dp, &
                                         -0.3620000000000023e-1_dp, 0.0_dp, 0.0_dp]
   !> Strictly lower triangles, row by row: (2,1), (3,1), (3,2), (4,1), ...
   real(dp), parameter :: a(15) = [0.1544e1_dp, 0.9466785280815826_dp, 0.2557011698983284_dp, &
      0.3314825187068521e1_dp, 0.2896124015972201e1_dp, 0.9986419139977817_dp, &
      0.1221224509226641e1_dp, 0.6019134481288629e1_dp, 0.1253708332932087e2_dp, &
      -0.6878860361058950_dp, 0.1221224509226641e1_dp, 0.6019134481288629e1_dp, &
      0.1253708332932087e2_dp, -0.6878860361058950_dp, 1.0_dp]
   real(dp), parameter :: c(15) = [-0.56688e1_dp, -0.2430093356833875e1_dp, &
      -0.2063599157091915_dp, -0.1073529058151375_dp, -0.9594562251023355e1_dp, &
      -0.2047028614809616e2_dp, 0.7496443313967647e1_dp, -0.1024680431464352e2_dp, &
      -0.3399990352819905e2_dp, 0.1170890893206160e2_dp, 0.8083246795921522e1_dp, &
      -0.7981132988064893e1_dp, -0.3152159432874371e2_dp, 0.1631930543123136e2_dp, &
      -0.6058818238834054e1_dp]
   real(dp), parameter :: m(ns) = [0.1221224509226641e1_dp, 0.6019134481288629e1_dp, &
      0.1253708332932087e2_dp, -0.6878860361058950_dp, 1.0_dp, 1.0_dp]

   !> The continuous extension's coefficients (rodas.f, d21..d25 and d31..d35): column k
   !> weighs the stages K_1..K_5 of the k-th correction term
   real(dp), parameter :: dense_d(5, 2) = reshape([10.12623508344586_dp, &
      -7.487995877610167_dp, -34.80091861555747_dp, -7.992771707568823_dp, &
      1.025137723295662_dp, -0.6762803392801253_dp, 6.087714651680015_dp, &
      16.43084320892478_dp, 24.76722511418386_dp, -6.594389125716872_dp], [5, 2])

   !> Step-size control: safety factor and bounds of the change (the factor goes with the
   !> error norm to the power -1/4, the estimate being of order 3: see root4)
   real(dp), parameter :: safety = 0.9_dp, fac_min = 0.2_dp, fac_max = 6.0_dp
   !> Under a smooth forcing, the share of the tolerance within which the continuous
   !> extension and the Hermite interpolant must agree at mid-step (see usharp_rodas4.inc)
   real(dp), parameter :: dense_share = 0.5_dp
   !> Step attempts a simulation may take in all, per branch of the history and per output
   !> time (see usharp_rodas4.inc)
   integer(int64), parameter :: steps_per_branch = 1000, steps_per_output = 20

contains

   !> Simulate the history from the virgin state, writing the response at the output times
   !> tout (s, non-decreasing, within the history's span). With effects, the extended model
   !> (usharp_effects): the model must then carry the effects' temperature and modulus
   !> already (effect_model); the initial state and the measured strain include R0, the drag
   !> offsets and the compliance, and the control value passes through the lag. The
   !> stress-channel shift is the caller's (output times).
   subroutine simulate_rosenbrock(model, hist, tout, opts, res, error, effects, states)
      class(model_type), intent(in) :: model
      type(history_type), intent(in) :: hist
      real(dp), intent(in) :: tout(:)
      type(solver_options), intent(in) :: opts
      type(sim_result), intent(out) :: res
      type(error_type), allocatable, intent(out) :: error
      type(test_effects), intent(in), optional :: effects
      !> With effects: carry p and R2 even where the effects leave them at rest (a search over
      !> an effect that acts through them then integrates one system on both sides of zero);
      !> by default only where they act (states_act)
      logical, intent(in), optional :: states
      call res%allocate(size(tout))
      call check_output_times(hist, tout, error)
      if (allocated(error)) return
      ! A smooth forcing is followed on its spline's knots, through a lag too
      if (hist%smooth()) then
         call simulate_on(model, hist%forcing(), tout, opts, res, error, effects, states)
      else
         call simulate_on(model, hist, tout, opts, res, error, effects, states)
      end if
   end subroutine simulate_rosenbrock

   !> simulate_rosenbrock on hist: a piecewise-linear history, or a smooth one's knots
   subroutine simulate_on(model, hist, tout, opts, res, error, effects, states)
      class(model_type), intent(in) :: model
      type(history_type), intent(in) :: hist
      real(dp), intent(in) :: tout(:)
      type(solver_options), intent(in) :: opts
      type(sim_result), intent(inout) :: res
      type(error_type), allocatable, intent(out) :: error
      type(test_effects), intent(in), optional :: effects
      logical, intent(in), optional :: states
      type(rate_system) :: sys
      real(dp) :: rtol, atol_strain, as, ar
      real(dp), allocatable :: y0(:), atol(:), ye(:)
      integer :: n, i

      call opts%tolerances('rodas4', rtol, atol_strain)
      if (hist%smooth() .and. .not. opts%rtol > 0.0_dp) rtol = rodas4_smooth_rtol
      as = atol_strain
      ar = atol_strain*model%youngs
      sys%extended = present(effects)
      if (sys%extended) then
         allocate (sys%model, source=model)
         sys%positive = model%positive_states()
         sys%eff = effects
         sys%stiffness = model%youngs/(1.0_dp + effects%compliance)
         sys%tc = hist%t
         sys%vc = hist%v
         ! The effects follow a smooth forcing as the plain model does (its turning points
         ! the only corners), a lag solved on each cubic piece; a piecewise-linear control
         ! is lagged on each segment
         sys%smooth = hist%smooth()
         if (sys%smooth) then
            if (effects%lag > 0.0_dp) then
               sys%mc = hist%d2
               sys%yk = lag_corners(hist%t, hist%v, effects%lag, hist%d2)
            else
               sys%pc = spline_power_form(hist%t, hist%v, hist%d2)
            end if
         else
            sys%yk = lag_corners(hist%t, hist%v, effects%lag)
         end if
         ! p and R2 only where they act: carried at rest they make a simulation of the Alloy
         ! 617 tests 1.10 times dearer (bench/measured.sh) and step otherwise
         sys%extra = 0
         if (states_act(effects)) sys%extra = 2
         if (present(states)) then
            if (states) sys%extra = 2
         end if
         allocate (ye(extended_size(model)))
         call extended_initial(model, effects, ye)
         n = model%n_uniaxial() + sys%extra
         y0 = ye(1:n)
         allocate (atol(n))
         if (allocated(hist%temp)) then
            sys%tt = hist%t
            sys%temp = hist%temp
         end if
         ! p is a strain, R2 a stress
         if (sys%extra > 0) atol(n - 1:n) = [as, ar]
      else
         call plain_system(model, hist, sys)
         n = model%n_uniaxial()
         allocate (y0(n), atol(n))
         call model%uniaxial_initial(y0)
      end if
      do i = 1, n - sys%extra
         atol(i) = merge(ar, as, model%uniaxial_is_stress(i))
      end do
      ! Small arrays of a size known at compile time where the model has one of these sizes
      select case (n)
      case (3); call integrate_3(sys, hist, tout, opts, y0, atol, rtol, res, error)
      case (4); call integrate_4(sys, hist, tout, opts, y0, atol, rtol, res, error)
      case (5); call integrate_5(sys, hist, tout, opts, y0, atol, rtol, res, error)
      case (6); call integrate_6(sys, hist, tout, opts, y0, atol, rtol, res, error)
      case (7); call integrate_7(sys, hist, tout, opts, y0, atol, rtol, res, error)
      case default; call integrate_n(n, sys, hist, tout, opts, y0, atol, rtol, res, error)
      end select
   end subroutine simulate_on

   !> The rates of the plain model under the load of hist (its smooth forcing, if it is one)
   subroutine plain_system(model, hist, sys)
      class(model_type), intent(in) :: model
      type(history_type), intent(in) :: hist
      type(rate_system), intent(inout) :: sys
      if (allocated(sys%model)) deallocate (sys%model)
      allocate (sys%model, source=model)
      sys%positive = model%positive_states()
      sys%stiffness = model%youngs
      sys%smooth = hist%smooth()
      if (sys%smooth) then
         sys%tc = hist%t
         sys%vc = hist%v
         sys%pc = spline_power_form(hist%t, hist%v, hist%d2)
      end if
      if (allocated(hist%temp)) then
         sys%tt = hist%t
         sys%temp = hist%temp
      end if
   end subroutine plain_system

   !> The integration from y0 (absolute tolerances atol) of a model with n states. Its body
   !> is compiled for each of the common numbers of states, so that its small arrays have a
   !> constant size: with n known only at run time a simulation took 30 % longer.
   ! fpm compiles a file again when its own text changes, not when a file it includes does.
   ! The body's hash stands here, checked by the test rodas4-body-hash-recorded, so that an
   ! edit of the body changes this file too and the build takes it:
   ! usharp_rodas4.inc FNV-1a C2C899A911D80B90
   subroutine integrate_3(sys, hist, tout, opts, y0, atol, rtol, res, error)
      integer, parameter :: n = 3
      include 'usharp_rodas4.inc'
   end subroutine integrate_3

   subroutine integrate_4(sys, hist, tout, opts, y0, atol, rtol, res, error)
      integer, parameter :: n = 4
      include 'usharp_rodas4.inc'
   end subroutine integrate_4

   subroutine integrate_5(sys, hist, tout, opts, y0, atol, rtol, res, error)
      integer, parameter :: n = 5
      include 'usharp_rodas4.inc'
   end subroutine integrate_5

   subroutine integrate_6(sys, hist, tout, opts, y0, atol, rtol, res, error)
      integer, parameter :: n = 6
      include 'usharp_rodas4.inc'
   end subroutine integrate_6

   subroutine integrate_7(sys, hist, tout, opts, y0, atol, rtol, res, error)
      integer, parameter :: n = 7
      include 'usharp_rodas4.inc'
   end subroutine integrate_7

   !> Any other number of states
   subroutine integrate_n(n, sys, hist, tout, opts, y0, atol, rtol, res, error)
      integer, intent(in) :: n
      include 'usharp_rodas4.inc'
   end subroutine integrate_n

   !> Stress, its derivative in eps_in and in time at (t, y): the load of the current
   !> segment, or for the extended model the lagged control value
   pure subroutine stress_of(sys, t, y, sigma, dsig, dsig_dt)
      type(rate_system), intent(in) :: sys
      real(dp), intent(in) :: t, y(:)
      real(dp), intent(out) :: sigma, dsig, dsig_dt
      real(dp) :: load, rate
      if (sys%extended .and. .not. sys%smooth) then
         call lagged_value(sys%tc, sys%vc, sys%yk, sys%k, sys%eff%lag, t, load, rate)
      else if (sys%smooth) then
         if (sys%hi > 0) then
            call smooth_load(sys, knot_piece(sys%tc, sys%lo, sys%hi, t), t, load, rate)
         else
            call smooth_load(sys, knot_piece(sys%tc, sys%k, sys%kend, t), t, load, rate)
         end if
      else
         load = sys%seg%value(t)
         rate = sys%seg%slope
      end if
      if (sys%seg%control == control_strain) then
         sigma = sys%stiffness*(load - y(1))
         dsig = -sys%stiffness
         dsig_dt = sys%stiffness*rate
      else
         sigma = load
         dsig = 0.0_dp
         dsig_dt = rate
      end if
   end subroutine stress_of

   !> The load of a smooth forcing and its rate at time t in piece k of its spline: the
   !> spline itself, or for the extended model with a lag the spline seen through it
   pure subroutine smooth_load(sys, k, t, load, rate)
      type(rate_system), intent(in) :: sys
      integer, intent(in) :: k
      real(dp), intent(in) :: t
      real(dp), intent(out) :: load, rate
      if (sys%extended .and. sys%eff%lag > 0.0_dp) then
         call lagged_value(sys%tc, sys%vc, sys%yk, k, sys%eff%lag, t, load, rate, sys%mc)
      else
         call power_piece(sys%tc(k), sys%pc(:, k), t, load, rate)
      end if
   end subroutine smooth_load

   !> The rates (1/s, unit/s) at time t (s) and state y; ok false outside the model (D <= 0)
   !> or when not finite
   pure subroutine rates(sys, t, y, f, ok)
      type(rate_system), intent(in) :: sys
      real(dp), intent(in) :: t
      real(dp), intent(in), contiguous :: y(:)
      real(dp), intent(out), contiguous :: f(:)
      logical, intent(out) :: ok
      real(dp) :: sigma, dsig, dsig_dt
      integer :: i
      f = 0.0_dp
      ! A loop: y(sys%positive) would make a temporary array at every call
      do i = 1, size(sys%positive)
         ok = y(sys%positive(i)) > 0.0_dp
         if (.not. ok) return
      end do
      ok = .true.
      call stress_of(sys, t, y, sigma, dsig, dsig_dt)
      call system_rates(sys, t, 0.0_dp, sigma, dsig, y, f, ok)
      if (ok) ok = all(ieee_is_finite(f))
   end subroutine rates

   !> Jacobian in the state and the rates' time derivative (through the load), both from
   !> the analytic derivative in the stress: the rates' Jacobian with d sigma/d eps_in = 1
   !> gives d f/d sigma as its first column. fy: the rates themselves (of the plain model
   !> the same bit for bit as those of rates); stress: the stress at (t, y)
   pure subroutine rates_jacobian(sys, t, y, jac, dfdt, fy, stress)
      type(rate_system), intent(in) :: sys
      real(dp), intent(in) :: t
      real(dp), intent(in), contiguous :: y(:)
      real(dp), intent(out), contiguous :: jac(:, :), dfdt(:)
      real(dp), intent(out), optional, contiguous :: fy(:)
      real(dp), intent(out), optional :: stress
      real(dp) :: sigma, dsig, dsig_dt, rate
      ! Arrays of a size known only at run time are made on the heap, at every step: the
      ! temperature's differences only, where they are needed; dfdt holds the rates first
      real(dp), allocatable :: fp(:), fm(:)
      real(dp), parameter :: dtemp = 0.01_dp
      logical :: ok
      integer :: k
      call stress_of(sys, t, y, sigma, dsig, dsig_dt)
      if (present(stress)) stress = sigma
      call system_rates(sys, t, 0.0_dp, sigma, 1.0_dp, y, dfdt, ok, jac)
      if (present(fy)) fy = dfdt
      dfdt = jac(:, 1)*dsig_dt
      jac(:, 1) = jac(:, 1)*dsig
      if (allocated(sys%temp) .and. ok) then
         ! Through the temperature too: central differences in T (K); theta(T) changes by
         ! some 6 % per K, so 0.01 K leaves a relative error near 1e-7
         k = temperature_segment(sys, t)
         rate = (sys%temp(k + 1) - sys%temp(k))/(sys%tt(k + 1) - sys%tt(k))
         if (rate /= 0.0_dp) then
            allocate (fp(size(y)), fm(size(y)))
            call system_rates(sys, t, dtemp, sigma, dsig, y, fp, ok)
            if (ok) call system_rates(sys, t, -dtemp, sigma, dsig, y, fm, ok)
            if (ok) dfdt = dfdt + (fp - fm)/(2.0_dp*dtemp)*rate
         end if
      end if
   end subroutine rates_jacobian

   !> The rates (and their Jacobian) of the model, or of the model with its effects, at
   !> stress sigma; under a temperature history those of a copy of the model moved to the
   !> temperature at time t (s) plus shift (K). ok false where the model cannot be moved there
   pure subroutine system_rates(sys, t, shift, sigma, dsig, y, f, ok, jac)
      type(rate_system), intent(in) :: sys
      real(dp), intent(in) :: t, shift, sigma, dsig
      real(dp), intent(in), contiguous :: y(:)
      real(dp), intent(out), contiguous :: f(:)
      logical, intent(out) :: ok
      real(dp), intent(out), optional, contiguous :: jac(:, :)
      class(model_type), allocatable :: m
      type(error_type), allocatable :: error
      integer :: k
      ok = .true.
      if (.not. allocated(sys%temp)) then
         call model_rates(sys, sys%model, sigma, dsig, y, f, jac)
         return
      end if
      k = temperature_segment(sys, t)
      allocate (m, source=sys%model)
      call m%set_temperature(sys%temp(k) + (sys%temp(k + 1) - sys%temp(k))* &
                             (t - sys%tt(k))/(sys%tt(k + 1) - sys%tt(k)) + shift, error)
      ok = .not. allocated(error)
      if (ok) then
         call model_rates(sys, m, sigma, dsig, y, f, jac)
      else
         ! Rates that no step accepts
         f = ieee_value(1.0_dp, ieee_quiet_nan)
         if (present(jac)) jac = 0.0_dp
      end if
   end subroutine system_rates

   !> The rates of model, plain or with the system's effects
   pure subroutine model_rates(sys, model, sigma, dsig, y, f, jac)
      type(rate_system), intent(in) :: sys
      class(model_type), intent(in) :: model
      real(dp), intent(in) :: sigma, dsig
      real(dp), intent(in), contiguous :: y(:)
      real(dp), intent(out), contiguous :: f(:)
      real(dp), intent(out), optional, contiguous :: jac(:, :)
      if (sys%extra > 0) then
         call extended_rates(model, sys%eff, sigma, y, f, dsig, jac)
      else
         call model%uniaxial_rates(sigma, dsig, y, f, jac)
      end if
   end subroutine model_rates

   !> The linear piece of a temperature history that holds time t (s): the current segment
   !> of the integration
   pure integer function temperature_segment(sys, t) result(k)
      type(rate_system), intent(in) :: sys
      real(dp), intent(in) :: t
      k = min(max(sys%k, 1), size(sys%tt) - 1)
      if (t > sys%tt(k + 1)) k = min(k + 1, size(sys%tt) - 1)
   end function temperature_segment
end module usharp_rosenbrock_driver
