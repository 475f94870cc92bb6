!> The Miller (1976) unified viscoplastic model: constants, the temperature function theta,
!> the initial drag stress and the rate equations with their analytic derivatives.
!>
!> Units: stresses in the model's unit (ksi or MPa), time in s, temperature in K, Q in cal/mol.
!> The scalar kernels (flow_rate, back_recovery, drag_recovery, drag_rate) act on equivalent
!> quantities, so the uniaxial form here and a multiaxial (J2) stress update share them.
module usharp_miller
   use, intrinsic :: ieee_arithmetic, only: ieee_is_finite, ieee_value, ieee_positive_inf
   use usharp_kinds, only: dp
   use usharp_error, only: error_type, fatal_error, stat_input
   use usharp_strings, only: str, lower
   implicit none
   private

   public :: miller_constants, miller_model, n_constants, constant_names
   public :: theta_miller, model_setup, check_constants, initial_drag
   public :: get_constant, set_constant, constant_index
   public :: flow_rate, back_recovery, drag_recovery, uniaxial_rates, rate_terms, rate_terms_at

   !> Universal gas constant in cal/(mol K), as the thesis uses it
   real(dp), parameter, public :: gas_constant = 1.9859_dp
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

   !> A Miller model at one temperature, ready for rate evaluation
   type :: miller_model
      type(miller_constants) :: c
      real(dp) :: temperature = 866.15_dp  !< K
      real(dp) :: tm = 1800.0_dp           !< melting temperature, K
      real(dp) :: youngs = 22.5e3_dp       !< Young's modulus, model stress unit
      real(dp) :: poisson = 0.3_dp         !< Poisson's ratio
      real(dp) :: d0_fixed = 0.0_dp        !< initial drag stress if > 0, else computed
      real(dp) :: d0_yield = 18.0_dp       !< YS in the D0 formula, model stress unit
      real(dp) :: d0_rate = 5.0e-5_dp      !< EE in the D0 formula, 1/s
      !> Derived by model_setup:
      real(dp) :: btheta = 0.0_dp          !< B*theta(T), 1/s
      real(dp) :: d0 = 0.0_dp              !< initial drag stress in use
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
         theta = exp(-q/(0.6_dp*gas_constant*tm)*(log(0.6_dp*tm/temperature) + 1.0_dp))
      else
         theta = exp(-q/(gas_constant*temperature))
      end if
   end function theta_miller

   !> Check that the constants and the test conditions are physically admissible
   pure subroutine check_constants(model, error)
      type(miller_model), intent(in) :: model
      type(error_type), allocatable, intent(out) :: error
      integer :: i
      character(len=:), allocatable :: msg
      do i = 1, n_constants
         msg = positive(get_constant(model%c, i), 'constant '//trim(constant_names(i)))
         if (len(msg) > 0) exit
      end do
      if (len(msg) == 0) msg = positive(model%tm, 'Tm')
      if (len(msg) == 0) msg = positive(model%temperature, 'temperature')
      if (len(msg) == 0) msg = positive(model%youngs, "Young's modulus E")
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

   !> Empty when val is finite and positive, else a message naming the quantity
   pure function positive(val, name) result(msg)
      real(dp), intent(in) :: val
      character(len=*), intent(in) :: name
      character(len=:), allocatable :: msg
      msg = ''
      if (.not. ieee_is_finite(val)) then
         msg = name//' is not finite'
      else if (val <= 0.0_dp) then
         msg = name//' must be > 0, got '//str(val)
      end if
   end function positive

   !> Initial drag stress from the constants (thesis Appendix A):
   !> D0 = (YS - 0.002*H1) / asinh((EE/(B*theta))**(1/n))**(2/3)
   pure subroutine initial_drag(model, d0, error)
      type(miller_model), intent(in) :: model
      real(dp), intent(out) :: d0
      type(error_type), allocatable, intent(out) :: error
      real(dp) :: num, den
      num = model%d0_yield - 0.002_dp*model%c%h1
      den = asinh((model%d0_rate/model%btheta)**(1.0_dp/model%c%n))**(2.0_dp/3.0_dp)
      d0 = num/den
      if (.not. ieee_is_finite(d0) .or. d0 <= 0.0_dp) then
         call fatal_error(error, 'initial drag stress D0 = (YS - 0.002*H1)/asinh(...)**(2/3) = '// &
            str(d0)//' is not positive; fix d0 or change H1')
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
         call fatal_error(error, 'B*theta(T) = '//str(model%btheta)//' 1/s is not representable')
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

   !> sinh(z)**n and (when asked) its derivative for z >= 0; non-finite beyond zmax. The
   !> rates alone skip the derivative's power and cosh: they are most of a simulation's time.
   elemental subroutine sinh_power(z, n, p, dp_dz)
      real(dp), intent(in) :: z, n
      real(dp), intent(out) :: p
      real(dp), intent(out), optional :: dp_dz
      real(dp) :: s
      if (z <= 0.0_dp) then
         p = 0.0_dp
         if (present(dp_dz)) dp_dz = merge(1.0_dp, 0.0_dp, abs(n - 1.0_dp) < epsilon(1.0_dp))
      else if (z > zmax) then
         p = ieee_value(1.0_dp, ieee_positive_inf)
         if (present(dp_dz)) dp_dz = p
      else
         ! exp(n*log(s)) rather than s**n: the same to rounding and half the cost of pow,
         ! which was a third of a simulation's time
         s = sinh(z)
         p = exp(n*log(s))
         if (present(dp_dz)) dp_dz = n*(p/s)*cosh(z)
      end if
   end subroutine sinh_power

   !> Equivalent inelastic strain rate f = B*theta*sinh((x/D)**1.5)**n (1/s) for the
   !> equivalent overstress x >= 0 and drag stress D > 0, with df/dx and df/dD if asked
   !> (both or neither).
   elemental subroutine flow_rate(model, x, d, f, f_x, f_d)
      type(miller_model), intent(in) :: model
      real(dp), intent(in) :: x, d
      real(dp), intent(out) :: f
      real(dp), intent(out), optional :: f_x, f_d
      real(dp) :: z, p, pz
      if (x <= 0.0_dp) then
         f = 0.0_dp
         if (present(f_x)) f_x = 0.0_dp
         if (present(f_d)) f_d = 0.0_dp
         return
      end if
      ! (x/d)**1.5 without pow
      z = (x/d)*sqrt(x/d)
      if (.not. present(f_x)) then
         call sinh_power(z, model%c%n, p)
         f = model%btheta*p
         return
      end if
      call sinh_power(z, model%c%n, p, pz)
      f = model%btheta*p
      f_x = model%btheta*pz*1.5_dp*sqrt(x/d)/d
      f_d = -model%btheta*pz*1.5_dp*z/d
   end subroutine flow_rate

   !> Static recovery of the back stress, g = H1*B*theta*sinh(A1*r)**n for r = |R| >= 0
   elemental subroutine back_recovery(model, r, g, g_r)
      type(miller_model), intent(in) :: model
      real(dp), intent(in) :: r
      real(dp), intent(out) :: g
      real(dp), intent(out), optional :: g_r
      real(dp) :: p, pz
      if (.not. present(g_r)) then
         call sinh_power(model%c%a1*r, model%c%n, p)
         g = model%c%h1*model%btheta*p
         return
      end if
      call sinh_power(model%c%a1*r, model%c%n, p, pz)
      g = model%c%h1*model%btheta*p
      g_r = model%c%h1*model%btheta*pz*model%c%a1
   end subroutine back_recovery

   !> Static recovery of the drag stress, h = H2*C2*B*theta*sinh(A2*D**3)**n
   elemental subroutine drag_recovery(model, d, h, h_d)
      type(miller_model), intent(in) :: model
      real(dp), intent(in) :: d
      real(dp), intent(out) :: h
      real(dp), intent(out), optional :: h_d
      real(dp) :: p, pz
      if (.not. present(h_d)) then
         call sinh_power(model%c%a2*d**3, model%c%n, p)
         h = model%c%h2*model%c%c2*model%btheta*p
         return
      end if
      call sinh_power(model%c%a2*d**3, model%c%n, p, pz)
      h = model%c%h2*model%c%c2*model%btheta*p
      h_d = model%c%h2*model%c%c2*model%btheta*pz*3.0_dp*model%c%a2*d**2
   end subroutine drag_recovery

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
            call flow_rate(model, x, d, t%f)
            call back_recovery(model, r, t%g)
            call drag_recovery(model, d, t%h)
            return
         end if
      end if
      call flow_rate(model, x, d, t%f, t%f_x, t%f_d)
      call back_recovery(model, r, t%g, t%g_r)
      call drag_recovery(model, d, t%h, t%h_d)
   end function rate_terms_at

   !> Uniaxial Miller rates (Eqs. 2-4) of the state y = (eps_in, R, D) at stress sigma,
   !> and their Jacobian jac(i,j) = d ydot_i / d y_j, where sigma depends on eps_in through
   !> dsig_depsin (-E under strain control, 0 under stress control).
   pure subroutine uniaxial_rates(model, sigma, dsig_depsin, y, ydot, jac)
      type(miller_model), intent(in) :: model
      real(dp), intent(in) :: sigma        !< stress, model unit
      real(dp), intent(in) :: dsig_depsin  !< d sigma / d eps_in
      real(dp), intent(in) :: y(3)         !< eps_in (-), R, D (model unit)
      real(dp), intent(out) :: ydot(3)     !< rates, 1/s and unit/s
      real(dp), intent(out), optional :: jac(3, 3)
      real(dp) :: s, sg, sgr, d
      type(rate_terms) :: t
      s = sigma - y(2)
      sg = sign(1.0_dp, s)
      sgr = sign(1.0_dp, y(2))
      d = y(3)
      t = rate_terms_at(model, abs(s), abs(y(2)), d, values_only=.not. present(jac))
      ydot(1) = t%f*sg
      ydot(2) = model%c%h1*ydot(1) - t%g*sgr
      ydot(3) = model%c%h2*t%f*t%w - t%h
      if (.not. present(jac)) return
      ! d(eps_in_dot)/dy: x = |sigma - R|, dx/deps_in = sg*dsig_depsin, dx/dR = -sg
      jac(1, 1) = t%f_x*dsig_depsin
      jac(1, 2) = -t%f_x
      jac(1, 3) = t%f_d*sg
      jac(2, :) = model%c%h1*jac(1, :)
      jac(2, 2) = jac(2, 2) - t%g_r
      jac(3, 1) = model%c%h2*t%f_x*sg*dsig_depsin*t%w
      jac(3, 2) = -model%c%h2*t%f_x*sg*t%w + model%c%h2*t%f*sgr
      jac(3, 3) = model%c%h2*(t%f_d*t%w - 3.0_dp*t%a*t%f*d**2) - t%h_d
   end subroutine uniaxial_rates
end module usharp_miller
