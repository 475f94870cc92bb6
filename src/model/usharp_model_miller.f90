!> The Miller (1976) unified viscoplastic model: constants, the temperature function theta,
!> the initial drag stress, the uniaxial rate equations with their analytic derivatives and
!> the implicit 3-D (J2) stress update with its consistent tangent; miller_model is its
!> implementation of usharp_model's model_type.
!>
!> Units: stresses in the model's unit (ksi or MPa), time in s, temperature in K, Q in cal/mol.
!> The scalar kernel (rate_laws: flow, back-stress and drag recovery) acts on equivalent
!> quantities, so the uniaxial form and the multiaxial (J2) stress update share it.
!>
!> The 3-D update is backward Euler over substeps of an increment, in the style of a UMAT.
!> State y = (inelastic strain (6), back stress R (6), drag stress D), Mandel vectors.
!> The multiaxial form (Kagawa and Asada 1983): with S = dev(sigma) - R, x = sqrt(3/2 S:S),
!> r = sqrt(3/2 R:R), f = f(x, D) of rate_laws:
!>    d(eps_in)/dt = 3/2 f S/x,   dR/dt = H1 f S/x - g(r) R/r,   dD/dt = H2 f (C2 + r - A2/A1 D^3) - h(D)
!> which reduces to Eqs. 2-4 in uniaxial stress.
module usharp_model_miller
   use, intrinsic :: ieee_arithmetic, only: ieee_is_finite, ieee_value, ieee_positive_inf
   use usharp_units, only: gas_constant
   use usharp_effect_values, only: test_effects
   use usharp_kinds, only: dp
   use usharp_math, only: exp_dp, log_dp, pow_dp, asinh_dp, sinh_power_dp
   use usharp_error, only: error_type, fatal_error
   use usharp_strings, only: str, lower, real_str
   use usharp_units, only: stress_factor
   use usharp_model, only: update_status_ok, update_status_cut, block_scalar, block_strain, &
                           block_stress
   use usharp_model_j2, only: j2_model, solve_dense
   implicit none
   private

   public :: miller_constants, miller_model, n_constants, constant_names
   public :: gas_constant
   public :: theta_miller, model_setup, check_constants, initial_drag
   public :: get_constant, set_constant, constant_index
   public :: rate_laws, rate_terms, rate_terms_at
   public :: n_state

   !> Universal gas constant in cal/(mol K), as the thesis uses it
   !> Number of named constants (A1, A2, B, C2, H1, H2, n, Q)
   integer, parameter :: n_constants = 8
   !> Names of the constants in the order used for fitting and logs
   character(len=2), parameter :: constant_names(n_constants) = &
      ['A1', 'A2', 'B ', 'C2', 'H1', 'H2', 'n ', 'Q ']
   !> Literature ranges of the constants for a model in ksi (thesis Table 1); H2, a single value
   !> there (100), gets 50-200. Multi-start draws its starts from this box by default.
   real(dp), parameter, public :: literature_low(n_constants) = &
      [0.8_dp, 7.42e-5_dp, 1.03e14_dp, 0.1_dp, 280.0_dp, 50.0_dp, 1.6_dp, 91000.0_dp]
   real(dp), parameter, public :: literature_high(n_constants) = &
      [0.93_dp, 5.94e-3_dp, 1.0e15_dp, 50.0_dp, 10000.0_dp, 200.0_dp, 5.8_dp, 104600.0_dp]
   !> Power of the stress unit in each constant's unit (A1 1/ksi, A2 1/ksi**3, C2 and H1 ksi)
   integer, parameter, public :: stress_power(n_constants) = [-1, -3, 0, 1, 1, 0, 0, 0]
   !> Largest argument passed to sinh; beyond it the rates are not representable
   real(dp), parameter :: zmax = 700.0_dp

   !> The Miller constants (units for a model in ksi; MPa analogously)
   type :: miller_constants
      real(dp) :: a1 = 0.8_dp       !< 1/ksi, back-stress recovery
      real(dp) :: a2 = 7.42e-5_dp   !< 1/ksi**3, drag recovery
      real(dp) :: b = 1.0e15_dp     !< 1/s, rate factor
      real(dp) :: c2 = 0.1_dp       !< ksi, drag hardening offset
      real(dp) :: h1 = 280.0_dp     !< ksi, kinematic hardening modulus
      real(dp) :: h2 = 100.0_dp     !< -, isotropic hardening coefficient
      real(dp) :: n = 5.8_dp        !< -, rate exponent
      real(dp) :: q = 91000.0_dp    !< cal/mol, activation energy
   end type miller_constants

   !> Number of 3-D state variables: inelastic strain (6), back stress (6), drag stress
   integer, parameter :: n_state = 13
   !> Number of uniaxial states: eps_in, R, D
   integer, parameter :: n_uniaxial = 3
   !> Properties of the drop-in user material (the original's TB,USER table)
   integer, parameter :: n_props = 13
   character(len=7), parameter :: prop_names(n_props) = [character(len=7) :: 'E', &
      'Poisson', 'A1', 'A2', 'B', 'C1', 'C2', 'k', 'H1', 'H2', 'n', 'Q', 'Tm']
   !> Newton iterations per (sub)increment and halvings of the increment before giving up
   integer, parameter :: max_newton = 25
   !> Backward Euler substeps per increment: the increments of an FE solution (0.15 s in the
   !> thesis's deck) are too coarse for first-order accuracy across the knee of the sinh law
   integer, parameter, public :: default_substeps = 8

   !> A Miller model at one temperature (temperature, tm, youngs and poisson from
   !> model_type), ready for rate evaluation
   type, extends(j2_model) :: miller_model
      type(miller_constants) :: c
      real(dp) :: d0_fixed = 0.0_dp        !< initial drag stress if > 0, else computed
      real(dp) :: d0_yield = 18.0_dp       !< YS in the D0 formula, model stress unit
      real(dp) :: d0_rate = 5.0e-5_dp      !< EE in the D0 formula, 1/s
      !> Derived by model_setup:
      real(dp) :: btheta = 0.0_dp          !< B*theta(T), 1/s
      real(dp) :: d0 = 0.0_dp              !< initial drag stress in use
   contains
      procedure :: name => miller_name
      procedure :: n_constants => miller_n_constants
      procedure :: constant_name => miller_constant_name
      procedure :: stress_power => miller_stress_power
      procedure :: literature_range => miller_literature_range
      procedure :: literature_units => miller_literature_units
      procedure :: get_constant => miller_get_constant
      procedure :: set_constant => miller_set_constant
      procedure :: constants_namelist => miller_constants_namelist
      procedure :: setup => miller_setup
      procedure :: n_uniaxial => miller_n_uniaxial
      procedure :: uniaxial_initial => miller_uniaxial_initial
      procedure :: uniaxial_is_stress => miller_uniaxial_is_stress
      procedure :: positive_states => miller_positive_states
      procedure :: uniaxial_rates => miller_uniaxial_rates
      procedure :: uniaxial_outputs => miller_uniaxial_outputs
      procedure :: n_state => miller_n_state
      procedure :: state_initial => miller_state_initial
      procedure :: local_step => local_newton
      procedure :: update_substeps => miller_update_substeps
      procedure :: state_outputs => miller_state_outputs
      procedure :: rates_constant_derivative => miller_rates_constant_derivative
      procedure :: n_props => miller_n_props
      procedure :: prop_name => miller_prop_name
      procedure :: to_props => miller_to_props
      procedure :: from_props => miller_from_props
      procedure :: fe_layout => miller_fe_layout
      procedure :: complete_state => miller_complete_state
      procedure :: fe_start_values => miller_fe_start_values
      procedure :: set_units => miller_set_units
      procedure :: set_option => miller_set_option
      procedure :: derived_values => miller_derived_values
      procedure :: set_temperature => miller_set_temperature
      procedure :: extended_rates => miller_extended_rates
      procedure :: extended_initial => miller_extended_initial
      procedure :: own_state_effects => miller_own_state_effects
   end type miller_model

   !> The scalar parts of the rates at equivalent overstress x, back stress r and drag stress D,
   !> with their derivatives: what the uniaxial and the multiaxial forms share
   type :: rate_terms
      real(dp) :: f = 0.0_dp, f_x = 0.0_dp, f_d = 0.0_dp  !< flow rate f(x, D), 1/s
      real(dp) :: g = 0.0_dp, g_r = 0.0_dp  !< back-stress recovery g(r)
      real(dp) :: h = 0.0_dp, h_d = 0.0_dp  !< drag recovery h(D)
      real(dp) :: w = 0.0_dp  !< C2 + r - (A2/A1) D**3
      real(dp) :: a = 0.0_dp  !< A2/A1
   end type rate_terms

contains

   !> Temperature function theta(T) of Miller's model (Eq. 5), both branches
   elemental real(dp) function theta_miller(q, tm, temperature) result(theta)
      real(dp), intent(in) :: q            !< activation energy, cal/mol
      real(dp), intent(in) :: tm           !< melting temperature, K
      real(dp), intent(in) :: temperature  !< K
      if (temperature <= 0.6_dp*tm) then
         theta = exp_dp(-q/(0.6_dp*gas_constant*tm)*(log_dp(0.6_dp*tm/temperature) + 1.0_dp))
      else
         theta = exp_dp(-q/(gas_constant*temperature))
      end if
   end function theta_miller

   !> Check that the constants and the test conditions are physically admissible
   pure subroutine check_constants(model, error)
      type(miller_model), intent(in) :: model
      type(error_type), allocatable, intent(out) :: error
      integer :: i
      character(len=:), allocatable :: msg
      do i = 1, n_constants
         call check_positive(get_constant(model%c, i), 'constant '//trim(constant_names(i)), msg)
         if (len(msg) > 0) exit
      end do
      if (len(msg) == 0) call check_positive(model%tm, 'Tm', msg)
      if (len(msg) == 0) call check_positive(model%temperature, 'temperature', msg)
      if (len(msg) == 0) call check_positive(model%youngs, "Young's modulus E", msg)
      if (len(msg) > 0) then
         call fatal_error(error, msg)
         return
      end if
      if (.not. ieee_is_finite(model%poisson) .or. model%poisson <= -1.0_dp &
          .or. model%poisson >= 0.5_dp) then
         call fatal_error(error, "Poisson's ratio must lie in (-1, 0.5), got "//str(model%poisson))
         return
      end if
      if (model%temperature >= model%tm) then
         call fatal_error(error, 'temperature '//str(model%temperature)// &
            ' K is at or above Tm = '//str(model%tm)//' K')
         return
      end if
      if (model%d0_fixed < 0.0_dp .or. .not. ieee_is_finite(model%d0_fixed)) then
         call fatal_error(error, 'fixed initial drag stress d0 must be >= 0 (0: computed)')
         return
      end if
   end subroutine check_constants

   !> Whether val is finite and positive: msg empty, else a message naming the quantity. (A
   !> subroutine: gfortran 12's deferred-length function results are not thread-safe, see
   !> usharp_strings, and the constants are checked in every simulation, side by side)
   pure subroutine check_positive(val, name, msg)
      real(dp), intent(in) :: val
      !> the quantity's name in the message
      character(len=*), intent(in) :: name
      character(len=:), allocatable, intent(out) :: msg
      msg = ''
      if (.not. ieee_is_finite(val)) then
         msg = name//' is not finite'
      else if (val <= 0.0_dp) then
         msg = name//' must be > 0, got '//str(val)
      end if
   end subroutine check_positive

   !> Initial drag stress from the constants (thesis Appendix A):
   !> D0 = (YS - 0.002*H1) / asinh((EE/(B*theta))**(1/n))**(2/3)
   pure subroutine initial_drag(model, d0, error)
      type(miller_model), intent(in) :: model
      real(dp), intent(out) :: d0
      type(error_type), allocatable, intent(out) :: error
      real(dp) :: num, den
      num = model%d0_yield - 0.002_dp*model%c%h1
      den = pow_dp(asinh_dp(pow_dp(model%d0_rate/model%btheta, 1.0_dp/model%c%n)), 2.0_dp/3.0_dp)
      d0 = num/den
      if (.not. ieee_is_finite(d0) .or. d0 <= 0.0_dp) then
         call fatal_error(error, 'initial drag stress D0 = (d0_yield - 0.002*H1)/asinh(...)**(2/3) = '// &
            str(d0)//' is not positive; fix d0, or a d0_yield above 0.002*H1')
      end if
   end subroutine initial_drag

   !> Validate the model and derive B*theta and the initial drag stress
   pure subroutine model_setup(model, error)
      type(miller_model), intent(inout) :: model
      type(error_type), allocatable, intent(out) :: error
      call check_constants(model, error)
      if (allocated(error)) return
      model%btheta = model%c%b*theta_miller(model%c%q, model%tm, model%temperature)
      if (.not. ieee_is_finite(model%btheta) .or. model%btheta <= 0.0_dp) then
         call fatal_error(error, 'B*theta(T) = '//real_str(model%btheta, 'es10.3')//' 1/s is not representable')
         return
      end if
      if (model%d0_fixed > 0.0_dp) then
         model%d0 = model%d0_fixed
      else
         call initial_drag(model, model%d0, error)
      end if
   end subroutine model_setup

   !> Constant number i (order of constant_names)
   pure real(dp) function get_constant(c, i) result(val)
      type(miller_constants), intent(in) :: c
      integer, intent(in) :: i
      select case (i)
      case (1); val = c%a1
      case (2); val = c%a2
      case (3); val = c%b
      case (4); val = c%c2
      case (5); val = c%h1
      case (6); val = c%h2
      case (7); val = c%n
      case default; val = c%q
      end select
   end function get_constant

   !> Set constant number i (order of constant_names)
   pure subroutine set_constant(c, i, val)
      type(miller_constants), intent(inout) :: c
      integer, intent(in) :: i
      real(dp), intent(in) :: val
      select case (i)
      case (1); c%a1 = val
      case (2); c%a2 = val
      case (3); c%b = val
      case (4); c%c2 = val
      case (5); c%h1 = val
      case (6); c%h2 = val
      case (7); c%n = val
      case default; c%q = val
      end select
   end subroutine set_constant

   !> Index of a constant by its (case-insensitive) name, 0 if unknown
   pure integer function constant_index(name) result(idx)
      character(len=*), intent(in) :: name
      integer :: i
      idx = 0
      do i = 1, n_constants
         if (lower(trim(adjustl(name))) == lower(trim(constant_names(i)))) idx = i
      end do
   end function constant_index

   !> The three power laws of the rates, each B theta sinh(z)**n: the flow f = B theta
   !> sinh((x/Df)**1.5)**n (1/s) at the equivalent overstress x >= 0 and the flow's drag
   !> stress Df > 0; the back stress's static recovery g = H1 B theta sinh(A1 r)**n at
   !> r = |R| >= 0; the drag stress's h = H2 C2 B theta sinh(A2 D**3)**n. With f_x, f_d, g_r
   !> and h_d if asked (all or none): the rates alone skip the derivatives. The three sinh
   !> powers are computed together (see sinh_power_dp): they are most of a simulation's time.
   !> sinh(z)**n is 0 at z <= 0 (its derivative 1 for n = 1, else 0) and not finite beyond zmax.
   pure subroutine rate_laws(model, x, df, r, d, f, g, h, f_x, f_d, g_r, h_d)
      type(miller_model), intent(in) :: model
      real(dp), intent(in) :: x    !< equivalent overstress (model unit)
      real(dp), intent(in) :: df   !< drag stress of the flow law (model unit)
      real(dp), intent(in) :: r    !< equivalent back stress (model unit)
      real(dp), intent(in) :: d    !< drag stress of its recovery (model unit)
      real(dp), intent(out) :: f   !< flow rate (1/s)
      real(dp), intent(out) :: g   !< back-stress recovery (model unit/s)
      real(dp), intent(out) :: h   !< drag recovery (model unit/s)
      !> df/dx, df/dDf, dg/dr and dh/dD
      real(dp), intent(out), optional :: f_x, f_d, g_r, h_d
      real(dp) :: z(3), p(3), pz(3)
      logical :: inside(3), flows
      ! (a NaN overstress flows, and comes out as NaN rates)
      flows = .not. x <= 0.0_dp
      ! (x/Df)**1.5 without pow
      z(1) = 0.0_dp
      if (flows) z(1) = (x/df)*sqrt(x/df)
      z(2) = model%c%a1*r
      z(3) = model%c%a2*d**3
      ! (NaN stays inside, and comes out as NaN)
      inside = .not. (z <= 0.0_dp .or. z > zmax)
      if (present(f_x)) then
         call sinh_power_dp(merge(z, 1.0_dp, inside), model%c%n, p, pz)
      else
         call sinh_power_dp(merge(z, 1.0_dp, inside), model%c%n, p)
      end if
      where (z <= 0.0_dp)
         p = 0.0_dp
         pz = merge(1.0_dp, 0.0_dp, abs(model%c%n - 1.0_dp) < epsilon(1.0_dp))
      elsewhere (z > zmax)
         p = ieee_value(1.0_dp, ieee_positive_inf)
         pz = p
      end where
      f = 0.0_dp
      if (flows) f = model%btheta*p(1)
      g = model%c%h1*model%btheta*p(2)
      h = model%c%h2*model%c%c2*model%btheta*p(3)
      if (.not. present(f_x)) return
      f_x = 0.0_dp
      f_d = 0.0_dp
      if (flows) then
         f_x = model%btheta*pz(1)*1.5_dp*sqrt(x/df)/df
         f_d = -model%btheta*pz(1)*1.5_dp*z(1)/df
      end if
      g_r = model%c%h1*model%btheta*pz(2)*model%c%a1
      h_d = model%c%h2*model%c%c2*model%btheta*pz(3)*3.0_dp*model%c%a2*d**2
   end subroutine rate_laws

   !> Evaluate the shared scalar terms; with values_only the derivatives are left at zero
   !> (the values are the same bit for bit)
   elemental function rate_terms_at(model, x, r, d, values_only) result(t)
      type(miller_model), intent(in) :: model
      real(dp), intent(in) :: x, r, d
      logical, intent(in), optional :: values_only
      type(rate_terms) :: t
      t%a = model%c%a2/model%c%a1
      t%w = model%c%c2 + r - t%a*d**3
      if (present(values_only)) then
         if (values_only) then
            call rate_laws(model, x, d, r, d, t%f, t%g, t%h)
            return
         end if
      end if
      call rate_laws(model, x, d, r, d, t%f, t%g, t%h, t%f_x, t%f_d, t%g_r, t%h_d)
   end function rate_terms_at

   !> Uniaxial Miller rates (Eqs. 2-4) of the state y = (eps_in, R, D) at stress sigma,
   !> and their Jacobian jac(i,j) = d ydot_i / d y_j, where sigma depends on eps_in through
   !> dsig_depsin (-E under strain control, 0 under stress control).
   pure subroutine miller_uniaxial_rates(self, sigma, dsig_depsin, y, ydot, jac)
      class(miller_model), intent(in) :: self
      real(dp), intent(in) :: sigma        !< stress, model unit
      real(dp), intent(in) :: dsig_depsin  !< d sigma / d eps_in
      real(dp), intent(in), contiguous :: y(:)         !< eps_in (-), R, D (model unit)
      real(dp), intent(out), contiguous :: ydot(:)     !< rates, 1/s and unit/s
      real(dp), intent(out), optional, contiguous :: jac(:, :)
      real(dp) :: s, sg, sgr, d
      type(rate_terms) :: t
      s = sigma - y(2)
      sg = sign(1.0_dp, s)
      sgr = sign(1.0_dp, y(2))
      d = y(3)
      t = rate_terms_at(self, abs(s), abs(y(2)), d, values_only=.not. present(jac))
      ydot(1) = t%f*sg
      ydot(2) = self%c%h1*ydot(1) - t%g*sgr
      ydot(3) = self%c%h2*t%f*t%w - t%h
      if (.not. present(jac)) return
      ! d(eps_in_dot)/dy: x = |sigma - R|, dx/deps_in = sg*dsig_depsin, dx/dR = -sg
      jac(1, 1) = t%f_x*dsig_depsin
      jac(1, 2) = -t%f_x
      jac(1, 3) = t%f_d*sg
      jac(2, :) = self%c%h1*jac(1, :)
      jac(2, 2) = jac(2, 2) - t%g_r
      jac(3, 1) = self%c%h2*t%f_x*sg*dsig_depsin*t%w
      jac(3, 2) = -self%c%h2*t%f_x*sg*t%w + self%c%h2*t%f*sgr
      jac(3, 3) = self%c%h2*(t%f_d*t%w - 3.0_dp*t%a*t%f*d**2) - t%h_d
   end subroutine miller_uniaxial_rates

   !> The local step of the 3-D update (j2_model): backward Euler on one subincrement by Newton's method with the analytic Jacobian.
   !> frac is the share of the whole strain increment reached at its end, dyde_prev the
   !> sensitivity of the starting state to the end strain of the whole increment; dyde
   !> returns the same for the new state (chain rule across subincrements).
   pure subroutine local_newton(self, g, p, eps, yprev, dt, frac, dyde_prev, y, dyde, status)
      class(miller_model), intent(in) :: self
      real(dp), intent(in) :: g, p(6, 6), eps(6), dt, frac
      real(dp), intent(in), contiguous :: yprev(:), dyde_prev(:, :)
      real(dp), intent(out), contiguous :: y(:), dyde(:, :)
      integer, intent(out) :: status
      real(dp) :: r(n_state), jac(n_state, n_state), drde(n_state, 6), dy(n_state, 1)
      real(dp) :: tol_strain, tol_stress, scale_s
      integer :: it, info
      status = update_status_cut
      y = yprev
      scale_s = max(maxval(abs(yprev(7:13))), 1.0e-3_dp*self%youngs)
      tol_strain = 1.0e-13_dp + 1.0e-11_dp*maxval(abs(yprev(1:6)))
      tol_stress = 1.0e-11_dp*scale_s
      do it = 1, max_newton
         call residual(self, g, p, eps, yprev, dt, y, r, jac, drde)
         if (.not. all(ieee_is_finite(r)) .or. .not. all(ieee_is_finite(jac))) return
         dy(:, 1) = -r
         call solve_dense(jac, dy, info)
         if (info /= 0 .or. .not. all(ieee_is_finite(dy))) return
         y = y + dy(:, 1)
         if (y(13) <= 0.0_dp) return
         if (maxval(abs(dy(1:6, 1))) <= tol_strain .and. maxval(abs(dy(7:13, 1))) <= tol_stress) then
            ! Converged: the sensitivity by the implicit function theorem at the solution,
            ! d r/d y * dy/de = -(d r/d eps * frac - dyde_prev)
            call residual(self, g, p, eps, yprev, dt, y, r, jac, drde)
            dyde = dyde_prev - frac*drde
            call solve_dense(jac, dyde, info)
            if (info /= 0 .or. .not. all(ieee_is_finite(dyde))) return
            status = update_status_ok
            return
         end if
      end do
   end subroutine local_newton

   !> Residual of backward Euler r(y) = y - yprev - dt*rates(y), its Jacobian d r/d y and
   !> its derivative with respect to the total strain at the end of the step
   pure subroutine residual(model, g, p, eps, yprev, dt, y, r, jac, drde)
      type(miller_model), intent(in) :: model
      real(dp), intent(in) :: g, p(6, 6), eps(6), yprev(n_state), dt, y(n_state)
      real(dp), intent(out) :: r(n_state), jac(n_state, n_state), drde(n_state, 6)
      real(dp) :: s(6), nh(6), mh(6), x, rb, d, f, f_x, f_d, gr, gr_r, h, h_d, w, a
      type(rate_terms) :: t
      real(dp) :: phi(6), psi(6), dphi(6, 6), dpsi(6, 6), fx_over, g_over, eye(6, 6)
      integer :: i
      eye = 0.0_dp
      do i = 1, 6
         eye(i, i) = 1.0_dp
      end do
      s = 2.0_dp*g*(matmul(p, eps) - y(1:6)) - y(7:12)
      x = sqrt(1.5_dp*dot_product(s, s))
      rb = sqrt(1.5_dp*dot_product(y(7:12), y(7:12)))
      d = y(13)
      t = rate_terms_at(model, x, rb, d)
      f = t%f; f_x = t%f_x; f_d = t%f_d
      gr = t%g; gr_r = t%g_r
      h = t%h; h_d = t%h_d
      w = t%w; a = t%a
      ! Unit directions and their derivatives; at x = 0 (or r = 0) the limits are used
      if (x > 0.0_dp) then
         nh = s/x
         fx_over = f/x
      else
         nh = 0.0_dp
         fx_over = 0.0_dp
      end if
      if (rb > 0.0_dp) then
         mh = y(7:12)/rb
         g_over = gr/rb
      else
         mh = 0.0_dp
         g_over = gr_r
      end if
      phi = f*nh
      psi = gr*mh
      dphi = 1.5_dp*(f_x - fx_over)*spread(nh, 2, 6)*spread(nh, 1, 6) + fx_over*eye
      dpsi = 1.5_dp*(gr_r - g_over)*spread(mh, 2, 6)*spread(mh, 1, 6) + g_over*eye

      r(1:6) = y(1:6) - yprev(1:6) - dt*1.5_dp*phi
      r(7:12) = y(7:12) - yprev(7:12) - dt*(model%c%h1*phi - psi)
      r(13) = y(13) - yprev(13) - dt*(model%c%h2*f*w - h)

      ! dS/d(eps_in) = -2G I, dS/dR = -I, dS/d(eps) = 2G P
      jac(1:6, 1:6) = eye + 3.0_dp*g*dt*dphi
      jac(1:6, 7:12) = 1.5_dp*dt*dphi
      jac(1:6, 13) = -1.5_dp*dt*f_d*nh
      jac(7:12, 1:6) = 2.0_dp*g*dt*model%c%h1*dphi
      jac(7:12, 7:12) = eye + dt*model%c%h1*dphi + dt*dpsi
      jac(7:12, 13) = -dt*model%c%h1*f_d*nh
      jac(13, 1:6) = 3.0_dp*g*dt*model%c%h2*w*f_x*nh
      jac(13, 7:12) = -dt*(-1.5_dp*model%c%h2*w*f_x*nh + 1.5_dp*model%c%h2*f*mh)
      jac(13, 13) = 1.0_dp - dt*(model%c%h2*(f_d*w - 3.0_dp*a*f*d**2) - h_d)

      drde(1:6, :) = -3.0_dp*g*dt*matmul(dphi, p)
      drde(7:12, :) = -2.0_dp*g*dt*model%c%h1*matmul(dphi, p)
      drde(13, :) = -3.0_dp*g*dt*model%c%h2*w*f_x*matmul(nh, p)
   end subroutine residual


   ! ---- miller_model as a model_type ----

   pure function miller_name(self) result(name)
      class(miller_model), intent(in) :: self
      character(len=:), allocatable :: name
      name = 'miller'
   end function miller_name

   pure integer function miller_n_constants(self) result(n)
      class(miller_model), intent(in) :: self
      n = n_constants
   end function miller_n_constants

   pure function miller_constant_name(self, i) result(name)
      class(miller_model), intent(in) :: self
      integer, intent(in) :: i
      character(len=:), allocatable :: name
      name = trim(constant_names(i))
   end function miller_constant_name

   pure integer function miller_stress_power(self, i) result(p)
      class(miller_model), intent(in) :: self
      integer, intent(in) :: i
      p = stress_power(i)
   end function miller_stress_power

   !> Thesis Table 1, in ksi
   pure subroutine miller_literature_range(self, i, low, high)
      class(miller_model), intent(in) :: self
      integer, intent(in) :: i
      real(dp), intent(out) :: low, high
      low = literature_low(i)
      high = literature_high(i)
   end subroutine miller_literature_range

   pure function miller_literature_units(self) result(name)
      class(miller_model), intent(in) :: self
      character(len=:), allocatable :: name
      name = 'ksi'
   end function miller_literature_units

   pure real(dp) function miller_get_constant(self, i) result(val)
      class(miller_model), intent(in) :: self
      integer, intent(in) :: i
      val = get_constant(self%c, i)
   end function miller_get_constant

   pure subroutine miller_set_constant(self, i, val)
      class(miller_model), intent(inout) :: self
      integer, intent(in) :: i
      real(dp), intent(in) :: val
      call set_constant(self%c, i, val)
   end subroutine miller_set_constant

   !> &constants: a1, a2, b, c2, h1, h2, n, q
   subroutine miller_constants_namelist(self, unset, ios, msg, text, unit)
      class(miller_model), intent(inout) :: self
      real(dp), intent(in) :: unset
      integer, intent(out) :: ios
      character(len=*), intent(out) :: msg
      character(len=*), intent(in), optional :: text(:)
      integer, intent(in), optional :: unit
      real(dp) :: a1, a2, b, c2, h1, h2, n, q
      namelist /constants/ a1, a2, b, c2, h1, h2, n, q
      ios = 0
      msg = ''
      if (present(text)) then
         a1 = unset; a2 = unset; b = unset; c2 = unset
         h1 = unset; h2 = unset; n = unset; q = unset
         read (text, nml=constants, iostat=ios, iomsg=msg)
         self%c = miller_constants(a1, a2, b, c2, h1, h2, n, q)
      end if
      if (present(unit)) then
         a1 = self%c%a1; a2 = self%c%a2; b = self%c%b; c2 = self%c%c2
         h1 = self%c%h1; h2 = self%c%h2; n = self%c%n; q = self%c%q
         write (unit, nml=constants, iostat=ios, iomsg=msg)
      end if
   end subroutine miller_constants_namelist

   pure subroutine miller_setup(self, error)
      class(miller_model), intent(inout) :: self
      type(error_type), allocatable, intent(out) :: error
      call model_setup(self, error)
   end subroutine miller_setup

   pure integer function miller_n_uniaxial(self) result(n)
      class(miller_model), intent(in) :: self
      n = n_uniaxial
   end function miller_n_uniaxial

   !> eps_in = 0, R = 0, D = D0
   pure subroutine miller_uniaxial_initial(self, y)
      class(miller_model), intent(in) :: self
      real(dp), intent(out) :: y(:)
      y = [0.0_dp, 0.0_dp, self%d0]
   end subroutine miller_uniaxial_initial

   pure logical function miller_uniaxial_is_stress(self, i) result(is_stress)
      class(miller_model), intent(in) :: self
      integer, intent(in) :: i
      is_stress = i > 1
   end function miller_uniaxial_is_stress

   !> The drag stress must stay positive
   pure function miller_positive_states(self) result(idx)
      class(miller_model), intent(in) :: self
      integer, allocatable :: idx(:)
      idx = [3]
   end function miller_positive_states

   pure subroutine miller_uniaxial_outputs(self, y, back, drag)
      class(miller_model), intent(in) :: self
      real(dp), intent(in) :: y(:)
      real(dp), intent(out) :: back, drag
      back = y(2)
      drag = y(3)
   end subroutine miller_uniaxial_outputs

   pure integer function miller_n_state(self) result(n)
      class(miller_model), intent(in) :: self
      n = n_state
   end function miller_n_state

   !> Inelastic strain and back stress zero, D = D0
   pure subroutine miller_state_initial(self, y)
      class(miller_model), intent(in) :: self
      real(dp), intent(out) :: y(:)
      y = 0.0_dp
      y(13) = self%d0
   end subroutine miller_state_initial

   pure integer function miller_update_substeps(self) result(n)
      class(miller_model), intent(in) :: self
      n = default_substeps
   end function miller_update_substeps

   !> The uniaxial back stress is R'_11 = 2/3 R: R = 3/2 R'_11
   pure subroutine miller_state_outputs(self, y, eps_in, back, drag)
      class(miller_model), intent(in) :: self
      real(dp), intent(in) :: y(:)
      real(dp), intent(out) :: eps_in, back, drag
      eps_in = y(1)
      back = 1.5_dp*y(7)
      drag = y(13)
   end subroutine miller_state_outputs

   !> Central differences with B*theta following B at the model's theta(T) and D0 kept (the
   !> sensitivity of the start value is the driver's)
   pure subroutine miller_rates_constant_derivative(self, i, sigma, dsig_depsin, y, dfdc)
      class(miller_model), intent(in) :: self
      integer, intent(in) :: i
      real(dp), intent(in) :: sigma, dsig_depsin
      real(dp), intent(in), contiguous :: y(:)
      real(dp), intent(out) :: dfdc(:)
      type(miller_model) :: mp, mm
      real(dp) :: c, h, theta, fp(n_uniaxial), fm(n_uniaxial)
      c = get_constant(self%c, i)
      h = 1.0e-6_dp*abs(c)
      theta = self%btheta/self%c%b
      mp = self
      mm = self
      call set_constant(mp%c, i, c + h)
      call set_constant(mm%c, i, c - h)
      mp%btheta = mp%c%b*theta
      mm%btheta = mm%c%b*theta
      call mp%uniaxial_rates(sigma, dsig_depsin, y, fp)
      call mm%uniaxial_rates(sigma, dsig_depsin, y, fm)
      dfdc = (fp - fm)/(2.0_dp*h)
   end subroutine miller_rates_constant_derivative

   pure integer function miller_n_props(self) result(n)
      class(miller_model), intent(in) :: self
      n = n_props
   end function miller_n_props

   pure function miller_prop_name(self, i) result(name)
      class(miller_model), intent(in) :: self
      integer, intent(in) :: i
      character(len=:), allocatable :: name
      name = trim(prop_names(i))
   end function miller_prop_name

   !> E, Poisson, A1, A2, B, C1, C2, k, H1, H2, n, Q, Tm: the original's TB,USER table (C1,
   !> carried for compatibility and not used by the published equations, is written as 0;
   !> k is the gas constant in cal/(mol K), theta uses Q/k)
   pure subroutine miller_to_props(self, props)
      class(miller_model), intent(in) :: self
      real(dp), intent(out) :: props(:)
      props = [self%youngs, self%poisson, self%c%a1, self%c%a2, self%c%b, 0.0_dp, self%c%c2, &
               gas_constant, self%c%h1, self%c%h2, self%c%n, self%c%q, self%tm]
   end subroutine miller_to_props

   pure subroutine miller_from_props(self, props, temp, message)
      class(miller_model), intent(inout) :: self
      real(dp), intent(in) :: props(:), temp
      character(len=*), intent(out) :: message
      type(error_type), allocatable :: error
      message = ''
      if (.not. (props(8) > 0.0_dp .and. props(8) < huge(1.0_dp))) then
         message = 'property 8, k (gas constant, cal/(mol K)), must be > 0'
         return
      end if
      self%youngs = props(1)
      self%poisson = props(2)
      self%c = miller_constants(a1=props(3), a2=props(4), b=props(5), c2=props(7), &
                                h1=props(9), h2=props(10), n=props(11), &
                                q=props(12)*gas_constant/props(8))
      self%tm = props(13)
      ! Property 14, where given and positive, is the initial drag stress D0 (the fit's, as
      ! usharp reports it): the formula's YS = 18 fits a model in ksi with the default d0
      ! settings only (for Table 4 in MPa it gives 8.97 MPa against 76.27)
      self%d0_fixed = 0.0_dp
      if (size(props) >= n_props + 1) then
         if (props(n_props + 1) > 0.0_dp .and. props(n_props + 1) < huge(1.0_dp)) &
            self%d0_fixed = props(n_props + 1)
      end if
      self%temperature = temp
      call model_setup(self, error)
      if (allocated(error)) message = error%message
   end subroutine miller_from_props

   !> State variables: 1-6 inelastic strain, 7 drag stress D (0 at the start: D0 is computed
   !> from the constants, as the original's TB,STATE initialised it), 8-13 back stress
   pure subroutine miller_fe_layout(self, y_first, code_first, kind)
      class(miller_model), intent(in) :: self
      integer, allocatable, intent(out) :: y_first(:), code_first(:), kind(:)
      y_first = [1, 7, 13]
      code_first = [1, 8, 7]
      kind = [block_strain, block_stress, block_scalar]
   end subroutine miller_fe_layout

   !> The drag stress (state variable 7) starts at D0
   pure subroutine miller_fe_start_values(self, pos, vals, names, notes)
      class(miller_model), intent(in) :: self
      integer, allocatable, intent(out) :: pos(:)
      real(dp), allocatable, intent(out) :: vals(:)
      character(len=:), allocatable, intent(out) :: names(:), notes(:)
      pos = [7]
      vals = [self%d0]
      names = [character(len=2) :: 'D0']
      notes = [character(len=22) :: 'initial drag stress D0']
   end subroutine miller_fe_start_values

   !> A drag stress not yet set (an FE code's zero) is D0
   pure subroutine miller_complete_state(self, y)
      class(miller_model), intent(in) :: self
      real(dp), intent(inout) :: y(:)
      if (y(13) <= 0.0_dp) y(13) = self%d0
   end subroutine miller_complete_state

   !> The initial drag stress in use
   pure subroutine miller_derived_values(self, names, vals)
      class(miller_model), intent(in) :: self
      character(len=:), allocatable, intent(out) :: names(:)
      real(dp), allocatable, intent(out) :: vals(:)
      names = [character(len=2) :: 'D0']
      vals = [self%d0]
   end subroutine miller_derived_values

   !> Temperature enters the rates only through B*theta(T) (Eq. 5); D0, the initial drag,
   !> stays that of the temperature the model was set up at
   pure subroutine miller_set_temperature(self, temperature, error)
      class(miller_model), intent(inout) :: self
      !> K
      real(dp), intent(in) :: temperature
      type(error_type), allocatable, intent(out) :: error
      self%temperature = temperature
      self%btheta = self%c%b*theta_miller(self%c%q, self%tm, temperature)
      if (.not. ieee_is_finite(self%btheta) .or. self%btheta <= 0.0_dp) &
         call fatal_error(error, 'B*theta(T) = '//real_str(self%btheta, 'es10.3')//' 1/s is not representable')
   end subroutine miller_set_temperature

   !> YS of the D0 formula: the thesis's 18 ksi in the model's unit
   pure subroutine miller_set_units(self, units)
      class(miller_model), intent(inout) :: self
      character(len=*), intent(in) :: units
      type(miller_model) :: defaults
      self%d0_yield = defaults%d0_yield*stress_factor('ksi', units)
   end subroutine miller_set_units

   !> d0 (fixed initial drag stress, 0: computed), d0_yield (YS) and d0_rate (EE) of the
   !> D0 formula
   pure subroutine miller_set_option(self, name, val, error)
      class(miller_model), intent(inout) :: self
      character(len=*), intent(in) :: name
      real(dp), intent(in) :: val
      type(error_type), allocatable, intent(out) :: error
      select case (name)
      case ('d0'); self%d0_fixed = val
      case ('d0_yield'); self%d0_yield = val
      case ('d0_rate'); self%d0_rate = val
      case default
         call fatal_error(error, name//' is not a setting of the miller model')
      end select
   end subroutine miller_set_option

   !> Rates of the extended state y = (eps_in, R, D, p, R2) at stress sigma: Eqs. 2-4 with the
   !> flow driven by sigma - R - R2 and the drag D*(1 - soften*(1 - exp(-soften_rate*p))) in
   !> the flow law (kept above 1e-3 D); dp/dt = |deps_in/dt|;
   !> dR2/dt = H3 deps_in/dt - gamma3 R2 dp/dt
   pure subroutine miller_extended_rates(self, eff, sigma, y, ydot, dsig_depsin, jac)
      class(miller_model), intent(in) :: self
      type(test_effects), intent(in) :: eff
      real(dp), intent(in) :: sigma
      real(dp), intent(in), contiguous :: y(:)
      real(dp), intent(out), contiguous :: ydot(:)
      real(dp), intent(in), optional :: dsig_depsin
      real(dp), intent(out), optional, contiguous :: jac(:, :)
      real(dp) :: s, f, f_x, f_d, g, g_r, h, h_d, d_flow, e, soft, dsoft, sg, sgr, w
      ! Of a size fixed at compile time: an array sized by y was made on the heap at every call
      real(dp) :: df(5)
      s = sigma - y(2) - y(5)
      if (abs(eff%soften) > 0.0_dp) then
         e = exp_dp(-eff%soften_rate*y(4))
         soft = 1.0_dp - eff%soften*(1.0_dp - e)
         dsoft = -eff%soften*eff%soften_rate*e
         if (soft < 1.0e-3_dp) then
            soft = 1.0e-3_dp
            dsoft = 0.0_dp
         end if
      else
         ! Most refits carry no softening: its exponential took a twentieth of a diagnosis
         soft = 1.0_dp
         dsoft = 0.0_dp
      end if
      d_flow = y(3)*soft
      if (present(jac)) then
         call rate_laws(self, abs(s), d_flow, abs(y(2)), y(3), f, g, h, f_x, f_d, g_r, h_d)
      else
         call rate_laws(self, abs(s), d_flow, abs(y(2)), y(3), f, g, h)
      end if
      w = self%c%c2 + abs(y(2)) - self%c%a2/self%c%a1*y(3)**3
      ydot(1) = sign(f, s)
      ydot(2) = self%c%h1*ydot(1) - sign(g, y(2))
      ydot(3) = self%c%h2*f*w - h
      ydot(4) = f
      ydot(5) = eff%h3*ydot(1) - eff%gamma3*y(5)*f
      if (.not. present(jac)) return
      ! df/dy through x = |s| and the flow's drag D*soft(p)
      sg = sign(1.0_dp, s)
      sgr = sign(1.0_dp, y(2))
      df = [f_x*sg*dsig_depsin, -f_x*sg, f_d*soft, f_d*y(3)*dsoft, -f_x*sg]
      jac(1, :) = sg*df
      jac(2, :) = self%c%h1*jac(1, :)
      jac(2, 2) = jac(2, 2) - g_r
      jac(3, :) = self%c%h2*w*df
      jac(3, 2) = jac(3, 2) + self%c%h2*f*sgr
      jac(3, 3) = jac(3, 3) - 3.0_dp*self%c%h2*f*self%c%a2/self%c%a1*y(3)**2 - h_d
      jac(4, :) = df
      jac(5, :) = eff%h3*jac(1, :) - eff%gamma3*y(5)*df
      jac(5, 5) = jac(5, 5) - eff%gamma3*f
   end subroutine miller_extended_rates

   !> The effects on the back stress and drag stress act (miller_extended_rates and _initial)
   pure logical function miller_own_state_effects(self)
      class(miller_model), intent(in) :: self
      miller_own_state_effects = .true.
   end function miller_own_state_effects

   !> The extended start: R0 = eff%r0, the drag D0*(1 + strength) + dD0; p = R2 = 0
   pure subroutine miller_extended_initial(self, eff, y)
      class(miller_model), intent(in) :: self
      type(test_effects), intent(in) :: eff
      real(dp), intent(out) :: y(:)
      y = [0.0_dp, eff%r0, self%d0*(1.0_dp + eff%strength) + eff%dd0, 0.0_dp, 0.0_dp]
   end subroutine miller_extended_initial
end module usharp_model_miller
