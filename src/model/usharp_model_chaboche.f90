!> A Chaboche-type unified viscoplastic model: Norton flow over a threshold, two
!> Armstrong-Frederick back stresses with power-law static recovery, and Voce isotropic
!> hardening. Its form is NEML's ChabocheFlowRule (constant fluidity) with the
!> ChabocheVoceRecovery hardening (isotropic recovery off), so constants carry over to and
!> from NEML and the publications that calibrate with it.
!>
!> Uniaxial form, state y = (eps_in, x1, x2, R), stresses in the model's unit (MPa), time in s:
!>    p_dot = < (|sigma - x1 - x2| - s0 - R) / eta >**n,   eps_in_dot = p_dot sign(sigma - x1 - x2)
!>    x_i_dot = C_i eps_in_dot - g_i x_i p_dot - A_i |x_i|**(m_i - 1) x_i
!>    R_dot = b (Q - R) p_dot
!> Multiaxial (J2) form: with S = dev(sigma) - X1 - X2, J = sqrt(3/2 S:S), n = S/J,
!> J_i = sqrt(3/2 X_i:X_i):
!>    d(eps_in)/dt = 3/2 p_dot n,   dX_i/dt = C_i p_dot n - g_i p_dot X_i - A_i J_i**(m_i - 1) X_i,
!>    dR/dt = b (Q - R) p_dot,  p_dot = <(J - s0 - R)/eta>**n,
!> which reduces to the uniaxial form with x_i = 3/2 X_i,11.
!> The 3-D update is backward Euler in Mandel form (11, 22, 33, sqrt2*12, sqrt2*23, sqrt2*13),
!> state y = (inelastic strain (6), X1 (6), X2 (6), R), with the consistent tangent.
!> chaboche_model is its implementation of usharp_model's model_type. The constants are those
!> at a reference temperature tref; with an activation energy (cal/mol, &model activation)
!> every rate process follows the Arrhenius factor
!>    theta = exp(-activation/k (1/T - 1/tref)):   p_dot -> theta p_dot (eta -> eta theta**(-1/n)),
!>    A_i -> theta A_i,
!> so the rates at T are theta times those at tref (temperature-compensated time); without it
!> the constants hold at every temperature.
module usharp_model_chaboche
   use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
   use usharp_units, only: gas_constant
   use usharp_kinds, only: dp
   use usharp_math, only: exp_dp, log_dp, pow_dp
   use usharp_error, only: error_type, fatal_error
   use usharp_strings, only: str, lower
   use usharp_model, only: update_status_ok, update_status_cut, block_scalar, block_strain, &
                           block_stress
   use usharp_model_j2, only: j2_model, solve_dense
   implicit none
   private

   public :: chaboche_constants, chaboche_model, chaboche_setup
   public :: chaboche_get_constant, chaboche_set_constant, chaboche_constant_index
   public :: chaboche_flow, chaboche_uniaxial_rates

   !> Number of back stresses
   integer, parameter, public :: chaboche_n_back = 2
   !> Number of named constants
   integer, parameter, public :: chaboche_n_constants = 13
   !> Names of the constants in the order used for fitting and logs
   character(len=6), parameter, public :: chaboche_constant_names(chaboche_n_constants) = &
      [character(len=6) :: 's0', 'eta', 'n', 'Q', 'b', 'C1', 'g1', 'C2', 'g2', 'A1', 'm1', 'A2', 'm2']
   !> Units of the constants for a model in MPa
   character(len=16), parameter, public :: chaboche_constant_units(chaboche_n_constants) = &
      [character(len=16) :: 'MPa', 'MPa s^(1/n)', '-', 'MPa', '-', 'MPa', '-', 'MPa', '-', &
       '1/(MPa^(m1-1) s)', '-', '1/(MPa^(m2-1) s)', '-']
   !> Default box of the constants for a model in MPa, wide enough for Chaboche sets of nickel
   !> alloys and austenitic steels between about 0.4 and 0.75 Tm (a multi-start box, not one
   !> publication's range; the search runs in log10 of the constants, so every bound is > 0);
   !> the recovery constants A_i span decades
   real(dp), parameter, public :: chaboche_literature_low(chaboche_n_constants) = &
      [1.0_dp, 50.0_dp, 2.0_dp, 1.0_dp, 0.5_dp, 1.0e4_dp, 100.0_dp, 1.0e3_dp, 5.0_dp, &
       1.0e-14_dp, 1.0_dp, 1.0e-14_dp, 1.0_dp]
   real(dp), parameter, public :: chaboche_literature_high(chaboche_n_constants) = &
      [150.0_dp, 3000.0_dp, 15.0_dp, 200.0_dp, 50.0_dp, 3.0e5_dp, 3000.0_dp, 5.0e4_dp, 500.0_dp, &
       1.0e-4_dp, 6.0_dp, 1.0e-4_dp, 6.0_dp]
   !> Power of the stress unit in each constant's unit. A_i is in MPa**(1 - m_i), a power that
   !> depends on m_i: it is given as 0, so its default box holds in MPa only
   integer, parameter, public :: chaboche_stress_power(chaboche_n_constants) = &
      [1, 1, 0, 1, 0, 1, 0, 1, 0, 0, 0, 0, 0]
   !> Number of uniaxial and of multiaxial state variables
   integer, parameter, public :: chaboche_n_uniaxial = 2 + chaboche_n_back
   integer, parameter, public :: chaboche_n_state = 7 + 6*chaboche_n_back
   !> Properties of the drop-in user material: E, Poisson's ratio, then the constants
   integer, parameter :: n_props = 2 + chaboche_n_constants
   !> Backward Euler substeps per increment by default, Newton iterations per substep
   integer, parameter, public :: chaboche_default_substeps = 8
   integer, parameter :: max_newton = 30

   !> The Chaboche constants (units for a model in MPa)
   type :: chaboche_constants
      real(dp) :: s0 = 0.0_dp        !< MPa, threshold (initial size of the elastic domain)
      real(dp) :: eta = 600.0_dp     !< MPa s^(1/n), Norton drag
      real(dp) :: n = 6.0_dp         !< -, Norton exponent
      real(dp) :: q = 20.0_dp        !< MPa, saturated isotropic hardening
      real(dp) :: b = 10.0_dp        !< -, Voce rate
      real(dp) :: c(chaboche_n_back) = [6.0e4_dp, 4.0e3_dp]  !< MPa, kinematic moduli
      real(dp) :: g(chaboche_n_back) = [1000.0_dp, 40.0_dp]  !< -, dynamic recovery
      real(dp) :: a(chaboche_n_back) = [0.0_dp, 1.0e-8_dp]   !< static recovery prefactors
      real(dp) :: m(chaboche_n_back) = [1.0_dp, 3.0_dp]      !< -, static recovery exponents
   end type chaboche_constants

   !> A Chaboche model at one temperature (temperature, youngs and poisson from model_type;
   !> the constants are those at that temperature)
   type, extends(j2_model) :: chaboche_model
      type(chaboche_constants) :: c
      !> cal/mol, activation energy of the rate processes (0: none)
      real(dp) :: activation = 0.0_dp
      !> K, the temperature the constants hold at (with an activation energy)
      real(dp) :: tref = 0.0_dp
      !> Derived at the model's temperature: eta's factor theta**(-1/n) and A_i's theta
      real(dp) :: eta_factor = 1.0_dp, rate_factor = 1.0_dp
   contains
      procedure :: name => ch_name
      procedure :: n_constants => ch_n_constants
      procedure :: constant_name => ch_constant_name
      procedure :: stress_power => ch_stress_power
      procedure :: literature_range => ch_literature_range
      procedure :: literature_units => ch_literature_units
      procedure :: get_constant => ch_get_constant
      procedure :: set_constant => ch_set_constant
      procedure :: constants_namelist => ch_constants_namelist
      procedure :: setup => chaboche_setup
      procedure :: n_uniaxial => ch_n_uniaxial
      procedure :: uniaxial_initial => ch_initial
      procedure :: uniaxial_is_stress => ch_uniaxial_is_stress
      procedure :: positive_states => ch_positive_states
      procedure :: uniaxial_rates => ch_uniaxial_rates
      procedure :: uniaxial_outputs => ch_uniaxial_outputs
      procedure :: n_state => ch_n_state
      procedure :: state_initial => ch_initial
      procedure :: local_step => local_newton
      procedure :: update_substeps => ch_update_substeps
      procedure :: state_outputs => ch_state_outputs
      procedure :: n_props => ch_n_props
      procedure :: prop_name => ch_prop_name
      procedure :: to_props => ch_to_props
      procedure :: from_props => ch_from_props
      procedure :: fe_layout => ch_fe_layout
      procedure :: complete_state => ch_complete_state
      procedure :: set_option => ch_set_option
      procedure :: derived_values => ch_derived_values
      procedure :: temperature_matters => ch_temperature_matters
   end type chaboche_model

contains

   !> Check that the constants and the elastic constants are admissible (nothing is derived)
   pure subroutine chaboche_setup(self, error)
      class(chaboche_model), intent(inout) :: self
      type(error_type), allocatable, intent(out) :: error
      integer :: i
      real(dp) :: v
      do i = 1, chaboche_n_constants
         v = chaboche_get_constant(self%c, i)
         if (.not. ieee_is_finite(v)) then
            call fatal_error(error, 'constant '//trim(chaboche_constant_names(i))//' is not finite')
            return
         end if
         select case (trim(chaboche_constant_names(i)))
         case ('eta')
            if (v <= 0.0_dp) call fatal_error(error, 'constant eta must be > 0, got '//str(v))
         case ('n', 'm1', 'm2')
            if (v < 1.0_dp) call fatal_error(error, 'constant '//trim(chaboche_constant_names(i))// &
                                             ' must be >= 1, got '//str(v))
         case default
            if (v < 0.0_dp) call fatal_error(error, 'constant '//trim(chaboche_constant_names(i))// &
                                             ' must be >= 0, got '//str(v))
         end select
         if (allocated(error)) return
      end do
      if (.not. ieee_is_finite(self%youngs) .or. self%youngs <= 0.0_dp) then
         call fatal_error(error, "Young's modulus E must be > 0, got "//str(self%youngs))
      else if (.not. ieee_is_finite(self%poisson) .or. self%poisson <= -1.0_dp &
               .or. self%poisson >= 0.5_dp) then
         call fatal_error(error, "Poisson's ratio must lie in (-1, 0.5), got "//str(self%poisson))
      end if
      if (allocated(error)) return
      self%eta_factor = 1.0_dp
      self%rate_factor = 1.0_dp
      if (self%activation > 0.0_dp) then
         if (.not. self%tref > 0.0_dp) then
            call fatal_error(error, 'an activation energy needs tref, the temperature the '// &
                             'constants hold at')
            return
         end if
         self%rate_factor = exp_dp(-self%activation/gas_constant* &
                                (1.0_dp/self%temperature - 1.0_dp/self%tref))
         self%eta_factor = pow_dp(self%rate_factor, -1.0_dp/self%c%n)
         if (.not. (ieee_is_finite(self%eta_factor) .and. self%rate_factor > 0.0_dp .and. &
                    ieee_is_finite(self%rate_factor))) &
            call fatal_error(error, 'the Arrhenius factor at '//str(self%temperature)//' K is '// &
                             'not representable (activation '//str(self%activation)//' cal/mol)')
      end if
   end subroutine chaboche_setup

   !> &model activation (cal/mol, >= 0) and tref (K, > 0: the temperature the constants
   !> hold at)
   !> The rates follow the temperature only through an activation energy
   pure logical function ch_temperature_matters(self)
      class(chaboche_model), intent(in) :: self
      ch_temperature_matters = self%activation > 0.0_dp
   end function ch_temperature_matters

   pure subroutine ch_set_option(self, name, val, error)
      class(chaboche_model), intent(inout) :: self
      character(len=*), intent(in) :: name
      real(dp), intent(in) :: val
      type(error_type), allocatable, intent(out) :: error
      select case (name)
      case ('activation')
         if (.not. (val >= 0.0_dp .and. ieee_is_finite(val))) then
            call fatal_error(error, 'activation = '//str(val)//' cal/mol must be >= 0')
            return
         end if
         self%activation = val
      case ('tref')
         if (.not. (val > 0.0_dp .and. ieee_is_finite(val))) then
            call fatal_error(error, 'tref = '//str(val)//' K must be > 0')
            return
         end if
         self%tref = val
      case default
         call fatal_error(error, name//' is not a setting of the chaboche model')
      end select
   end subroutine ch_set_option

   !> With an activation energy: the Arrhenius factor at the model's temperature
   pure subroutine ch_derived_values(self, names, vals)
      class(chaboche_model), intent(in) :: self
      character(len=:), allocatable, intent(out) :: names(:)
      real(dp), allocatable, intent(out) :: vals(:)
      if (self%activation > 0.0_dp) then
         names = [character(len=5) :: 'theta']
         vals = [self%rate_factor]
      else
         allocate (character(len=1) :: names(0))
         allocate (vals(0))
      end if
   end subroutine ch_derived_values

   !> Constant number i (order of chaboche_constant_names)
   pure real(dp) function chaboche_get_constant(c, i) result(val)
      type(chaboche_constants), intent(in) :: c
      integer, intent(in) :: i
      select case (i)
      case (1); val = c%s0
      case (2); val = c%eta
      case (3); val = c%n
      case (4); val = c%q
      case (5); val = c%b
      case (6, 8); val = c%c((i - 4)/2)
      case (7, 9); val = c%g((i - 5)/2)
      case (10, 12); val = c%a((i - 8)/2)
      case default; val = c%m((i - 9)/2)
      end select
   end function chaboche_get_constant

   !> Set constant number i (order of chaboche_constant_names)
   pure subroutine chaboche_set_constant(c, i, val)
      type(chaboche_constants), intent(inout) :: c
      integer, intent(in) :: i
      real(dp), intent(in) :: val
      select case (i)
      case (1); c%s0 = val
      case (2); c%eta = val
      case (3); c%n = val
      case (4); c%q = val
      case (5); c%b = val
      case (6, 8); c%c((i - 4)/2) = val
      case (7, 9); c%g((i - 5)/2) = val
      case (10, 12); c%a((i - 8)/2) = val
      case default; c%m((i - 9)/2) = val
      end select
   end subroutine chaboche_set_constant

   !> Index of a constant by its (case-insensitive) name, 0 if unknown
   pure integer function chaboche_constant_index(name) result(idx)
      character(len=*), intent(in) :: name
      integer :: i
      idx = 0
      do i = 1, chaboche_n_constants
         if (lower(trim(adjustl(name))) == lower(trim(chaboche_constant_names(i)))) idx = i
      end do
   end function chaboche_constant_index

   !> Equivalent inelastic strain rate p_dot = <(x - s0 - R)/eta>**n (1/s) at equivalent
   !> effective stress x and isotropic hardening R, and its derivative with respect to the
   !> overstress x - s0 - R
   elemental subroutine chaboche_flow(model, x, r, f, f_o)
      type(chaboche_model), intent(in) :: model
      real(dp), intent(in) :: x, r
      real(dp), intent(out) :: f, f_o
      real(dp) :: z
      z = (x - model%c%s0 - r)/(model%c%eta*model%eta_factor)
      if (z <= 0.0_dp) then
         f = 0.0_dp
         f_o = 0.0_dp
      else
         f = exp_dp(model%c%n*log_dp(z))
         f_o = model%c%n*f/(z*model%c%eta*model%eta_factor)
      end if
   end subroutine chaboche_flow

   !> Static recovery rate magnitude A |x|**(m - 1) (times x gives the recovery) and its
   !> derivative with respect to |x|
   elemental subroutine recovery(a, m, x, h, h_x)
      real(dp), intent(in) :: a, m, x
      real(dp), intent(out) :: h, h_x
      if (a <= 0.0_dp) then
         h = 0.0_dp
         h_x = 0.0_dp
      else if (m <= 1.0_dp) then
         h = a
         h_x = 0.0_dp
      else if (x <= 0.0_dp) then
         h = 0.0_dp
         h_x = 0.0_dp
      else
         h = a*exp_dp((m - 1.0_dp)*log_dp(x))
         h_x = (m - 1.0_dp)*h/x
      end if
   end subroutine recovery

   !> Uniaxial rates of y = (eps_in, x1, x2, R) at stress sigma and their Jacobian
   !> jac(i,j) = d ydot_i / d y_j, where sigma depends on eps_in through dsig_depsin
   !> (-E under strain control, 0 under stress control)
   pure subroutine chaboche_uniaxial_rates(model, sigma, dsig_depsin, y, ydot, jac)
      type(chaboche_model), intent(in) :: model
      real(dp), intent(in) :: sigma        !< stress, model unit
      real(dp), intent(in) :: dsig_depsin  !< d sigma / d eps_in
      real(dp), intent(in) :: y(chaboche_n_uniaxial)      !< eps_in (-), x1, x2, R (model unit)
      real(dp), intent(out) :: ydot(chaboche_n_uniaxial)  !< rates, 1/s and unit/s
      real(dp), intent(out), optional :: jac(chaboche_n_uniaxial, chaboche_n_uniaxial)
      real(dp) :: s, sg, f, f_o, dp_dy(chaboche_n_uniaxial), h, h_x
      integer :: i, nr
      nr = chaboche_n_uniaxial
      s = sigma - sum(y(2:nr - 1))
      sg = sign(1.0_dp, s)
      call chaboche_flow(model, abs(s), y(nr), f, f_o)
      ydot(1) = f*sg
      do i = 1, chaboche_n_back
         call recovery(model%c%a(i)*model%rate_factor, model%c%m(i), abs(y(1 + i)), h, h_x)
         ydot(1 + i) = model%c%c(i)*ydot(1) - model%c%g(i)*y(1 + i)*f - h*y(1 + i)
      end do
      ydot(nr) = model%c%b*(model%c%q - y(nr))*f
      if (.not. present(jac)) return
      ! d p_dot / d y: the overstress |s| - s0 - R
      dp_dy(1) = f_o*sg*dsig_depsin
      dp_dy(2:nr - 1) = -f_o*sg
      dp_dy(nr) = -f_o
      jac(1, :) = sg*dp_dy
      do i = 1, chaboche_n_back
         call recovery(model%c%a(i)*model%rate_factor, model%c%m(i), abs(y(1 + i)), h, h_x)
         jac(1 + i, :) = model%c%c(i)*jac(1, :) - model%c%g(i)*y(1 + i)*dp_dy
         ! d(h(|x|) x)/dx = h + h_x |x|
         jac(1 + i, 1 + i) = jac(1 + i, 1 + i) - model%c%g(i)*f - h - h_x*abs(y(1 + i))
      end do
      jac(nr, :) = model%c%b*(model%c%q - y(nr))*dp_dy
      jac(nr, nr) = jac(nr, nr) - model%c%b*f
   end subroutine chaboche_uniaxial_rates

   !> The local step of the 3-D update (j2_model): backward Euler on one subincrement by
   !> Newton's method with the analytic Jacobian; dyde carries the sensitivity of the state
   !> to the end strain of the whole increment
   pure subroutine local_newton(self, g, p, eps, yprev, dt, frac, dyde_prev, y, dyde, status)
      class(chaboche_model), intent(in) :: self
      real(dp), intent(in) :: g, p(6, 6), eps(6), dt, frac
      real(dp), intent(in), contiguous :: yprev(:), dyde_prev(:, :)
      real(dp), intent(out), contiguous :: y(:), dyde(:, :)
      integer, intent(out) :: status
      real(dp) :: r(chaboche_n_state), jac(chaboche_n_state, chaboche_n_state)
      real(dp) :: drde(chaboche_n_state, 6), dy(chaboche_n_state, 1), tol_strain, tol_stress
      integer :: it, info, ns
      ns = chaboche_n_state
      status = update_status_cut
      y = yprev
      tol_strain = 1.0e-13_dp + 1.0e-11_dp*maxval(abs(yprev(1:6)))
      tol_stress = 1.0e-11_dp*max(maxval(abs(yprev(7:ns))), 1.0e-3_dp*self%youngs)
      do it = 1, max_newton
         call residual(self, g, p, eps, yprev, dt, y, r, jac, drde)
         if (.not. all(ieee_is_finite(r)) .or. .not. all(ieee_is_finite(jac))) return
         dy(:, 1) = -r
         call solve_dense(jac, dy, info)
         if (info /= 0 .or. .not. all(ieee_is_finite(dy))) return
         y = y + dy(:, 1)
         if (maxval(abs(dy(1:6, 1))) <= tol_strain .and. maxval(abs(dy(7:ns, 1))) <= tol_stress) then
            call residual(self, g, p, eps, yprev, dt, y, r, jac, drde)
            dyde = dyde_prev - frac*drde
            call solve_dense(jac, dyde, info)
            if (info /= 0 .or. .not. all(ieee_is_finite(dyde))) return
            status = update_status_ok
            return
         end if
      end do
   end subroutine local_newton

   !> Residual of backward Euler r(y) = y - yprev - dt*rates(y), its Jacobian d r/d y and its
   !> derivative with respect to the total strain at the end of the step
   pure subroutine residual(model, g, p, eps, yprev, dt, y, r, jac, drde)
      type(chaboche_model), intent(in) :: model
      real(dp), intent(in) :: g, p(6, 6), eps(6), yprev(chaboche_n_state), dt, y(chaboche_n_state)
      real(dp), intent(out) :: r(chaboche_n_state), jac(chaboche_n_state, chaboche_n_state)
      real(dp), intent(out) :: drde(chaboche_n_state, 6)
      real(dp) :: s(6), nh(6), x, f, f_o, f_over, dphi(6, 6), eye(6, 6), xi(6), ji, h, h_x
      real(dp) :: mh(6), dpsi(6, 6), ci, gi, rr, bq, nhp(6)
      integer :: i, j, lo, hi, lo2, nr
      nr = chaboche_n_state
      eye = 0.0_dp
      do i = 1, 6
         eye(i, i) = 1.0_dp
      end do
      s = 2.0_dp*g*(matmul(p, eps) - y(1:6))
      do i = 1, chaboche_n_back
         s = s - y(1 + 6*i:6 + 6*i)
      end do
      x = sqrt(1.5_dp*dot_product(s, s))
      rr = y(nr)
      call chaboche_flow(model, x, rr, f, f_o)
      if (x > 0.0_dp) then
         nh = s/x
         f_over = f/x
      else
         nh = 0.0_dp
         f_over = 0.0_dp
      end if
      nhp = matmul(nh, p)
      ! d(f nh)/dS
      dphi = 1.5_dp*(f_o - f_over)*spread(nh, 2, 6)*spread(nh, 1, 6) + f_over*eye
      bq = model%c%b*(model%c%q - rr)

      r(1:6) = y(1:6) - yprev(1:6) - dt*1.5_dp*f*nh
      jac = 0.0_dp
      jac(1:6, 1:6) = eye + 3.0_dp*g*dt*dphi
      jac(1:6, nr) = 1.5_dp*dt*f_o*nh
      drde(1:6, :) = -3.0_dp*g*dt*matmul(dphi, p)
      do i = 1, chaboche_n_back
         lo = 1 + 6*i
         hi = lo + 5
         xi = y(lo:hi)
         ci = model%c%c(i)
         gi = model%c%g(i)
         ji = sqrt(1.5_dp*dot_product(xi, xi))
         call recovery(model%c%a(i)*model%rate_factor, model%c%m(i), ji, h, h_x)
         ! d(h(J_i) X_i)/dX_i = h I + h_x X_i (x) 3/2 X_i/J_i
         if (ji > 0.0_dp) then
            mh = xi/ji
         else
            mh = 0.0_dp
         end if
         dpsi = h*eye + 1.5_dp*h_x*ji*spread(mh, 2, 6)*spread(mh, 1, 6)
         r(lo:hi) = xi - yprev(lo:hi) - dt*(ci*f*nh - gi*f*xi - h*xi)
         jac(1:6, lo:hi) = 1.5_dp*dt*dphi
         jac(lo:hi, 1:6) = dt*(2.0_dp*g*ci*dphi - 3.0_dp*g*gi*f_o*spread(xi, 2, 6)*spread(nh, 1, 6))
         do j = 1, chaboche_n_back
            lo2 = 1 + 6*j
            jac(lo:hi, lo2:lo2 + 5) = dt*(ci*dphi - 1.5_dp*gi*f_o*spread(xi, 2, 6)*spread(nh, 1, 6))
         end do
         jac(lo:hi, lo:hi) = jac(lo:hi, lo:hi) + eye + dt*(gi*f*eye + dpsi)
         jac(lo:hi, nr) = dt*f_o*(ci*nh - gi*xi)
         drde(lo:hi, :) = -2.0_dp*g*dt*(ci*matmul(dphi, p) &
                                       - 1.5_dp*gi*f_o*spread(xi, 2, 6)*spread(nhp, 1, 6))
         jac(nr, lo:hi) = 1.5_dp*dt*bq*f_o*nh
      end do
      r(nr) = rr - yprev(nr) - dt*bq*f
      jac(nr, 1:6) = 3.0_dp*g*dt*bq*f_o*nh
      jac(nr, nr) = 1.0_dp + dt*model%c%b*f + dt*bq*f_o
      drde(nr, :) = -3.0_dp*g*dt*bq*f_o*nhp
   end subroutine residual

   ! ---- chaboche_model as a model_type ----

   pure function ch_name(self) result(name)
      class(chaboche_model), intent(in) :: self
      character(len=:), allocatable :: name
      name = 'chaboche'
   end function ch_name

   pure integer function ch_n_constants(self) result(n)
      class(chaboche_model), intent(in) :: self
      n = chaboche_n_constants
   end function ch_n_constants

   pure function ch_constant_name(self, i) result(name)
      class(chaboche_model), intent(in) :: self
      integer, intent(in) :: i
      character(len=:), allocatable :: name
      name = trim(chaboche_constant_names(i))
   end function ch_constant_name

   pure integer function ch_stress_power(self, i) result(p)
      class(chaboche_model), intent(in) :: self
      integer, intent(in) :: i
      p = chaboche_stress_power(i)
   end function ch_stress_power

   pure subroutine ch_literature_range(self, i, low, high)
      class(chaboche_model), intent(in) :: self
      integer, intent(in) :: i
      real(dp), intent(out) :: low, high
      low = chaboche_literature_low(i)
      high = chaboche_literature_high(i)
   end subroutine ch_literature_range

   pure function ch_literature_units(self) result(name)
      class(chaboche_model), intent(in) :: self
      character(len=:), allocatable :: name
      name = 'MPa'
   end function ch_literature_units

   pure real(dp) function ch_get_constant(self, i) result(val)
      class(chaboche_model), intent(in) :: self
      integer, intent(in) :: i
      val = chaboche_get_constant(self%c, i)
   end function ch_get_constant

   pure subroutine ch_set_constant(self, i, val)
      class(chaboche_model), intent(inout) :: self
      integer, intent(in) :: i
      real(dp), intent(in) :: val
      call chaboche_set_constant(self%c, i, val)
   end subroutine ch_set_constant

   !> &constants: s0, eta, n, q, b, c1, g1, c2, g2, a1, m1, a2, m2
   subroutine ch_constants_namelist(self, unset, ios, msg, text, unit)
      class(chaboche_model), intent(inout) :: self
      real(dp), intent(in) :: unset
      integer, intent(out) :: ios
      character(len=*), intent(out) :: msg
      character(len=*), intent(in), optional :: text(:)
      integer, intent(in), optional :: unit
      real(dp) :: s0, eta, n, q, b, c1, g1, c2, g2, a1, m1, a2, m2
      namelist /constants/ s0, eta, n, q, b, c1, g1, c2, g2, a1, m1, a2, m2
      ios = 0
      msg = ''
      if (present(text)) then
         s0 = unset; eta = unset; n = unset; q = unset; b = unset
         c1 = unset; g1 = unset; c2 = unset; g2 = unset
         a1 = unset; m1 = unset; a2 = unset; m2 = unset
         read (text, nml=constants, iostat=ios, iomsg=msg)
         self%c = chaboche_constants(s0, eta, n, q, b, [c1, c2], [g1, g2], [a1, a2], [m1, m2])
      end if
      if (present(unit)) then
         s0 = self%c%s0; eta = self%c%eta; n = self%c%n; q = self%c%q; b = self%c%b
         c1 = self%c%c(1); g1 = self%c%g(1); c2 = self%c%c(2); g2 = self%c%g(2)
         a1 = self%c%a(1); m1 = self%c%m(1); a2 = self%c%a(2); m2 = self%c%m(2)
         write (unit, nml=constants, iostat=ios, iomsg=msg)
      end if
   end subroutine ch_constants_namelist

   pure integer function ch_n_uniaxial(self) result(n)
      class(chaboche_model), intent(in) :: self
      n = chaboche_n_uniaxial
   end function ch_n_uniaxial

   !> The virgin state (uniaxial and 3-D): all zero
   pure subroutine ch_initial(self, y)
      class(chaboche_model), intent(in) :: self
      real(dp), intent(out) :: y(:)
      y = 0.0_dp
   end subroutine ch_initial

   pure logical function ch_uniaxial_is_stress(self, i) result(is_stress)
      class(chaboche_model), intent(in) :: self
      integer, intent(in) :: i
      is_stress = i > 1
   end function ch_uniaxial_is_stress

   !> No state must stay positive (the back stresses change sign, R is bounded by the rates)
   pure function ch_positive_states(self) result(idx)
      class(chaboche_model), intent(in) :: self
      integer, allocatable :: idx(:)
      allocate (idx(0))
   end function ch_positive_states

   pure subroutine ch_uniaxial_rates(self, sigma, dsig_depsin, y, ydot, jac)
      class(chaboche_model), intent(in) :: self
      real(dp), intent(in) :: sigma, dsig_depsin
      real(dp), intent(in), contiguous :: y(:)
      real(dp), intent(out), contiguous :: ydot(:)
      real(dp), intent(out), optional, contiguous :: jac(:, :)
      call chaboche_uniaxial_rates(self, sigma, dsig_depsin, y, ydot, jac)
   end subroutine ch_uniaxial_rates

   !> Back stress: the sum of the back stresses; drag stress: the current threshold s0 + R
   pure subroutine ch_uniaxial_outputs(self, y, back, drag)
      class(chaboche_model), intent(in) :: self
      real(dp), intent(in) :: y(:)
      real(dp), intent(out) :: back, drag
      back = sum(y(2:chaboche_n_uniaxial - 1))
      drag = self%c%s0 + y(chaboche_n_uniaxial)
   end subroutine ch_uniaxial_outputs

   pure integer function ch_n_state(self) result(n)
      class(chaboche_model), intent(in) :: self
      n = chaboche_n_state
   end function ch_n_state

   pure integer function ch_update_substeps(self) result(n)
      class(chaboche_model), intent(in) :: self
      n = chaboche_default_substeps
   end function ch_update_substeps

   !> Uniaxial back stress x = 3/2 X_11 summed over the back stresses; threshold s0 + R
   pure subroutine ch_state_outputs(self, y, eps_in, back, drag)
      class(chaboche_model), intent(in) :: self
      real(dp), intent(in) :: y(:)
      real(dp), intent(out) :: eps_in, back, drag
      integer :: i
      eps_in = y(1)
      back = 0.0_dp
      do i = 1, chaboche_n_back
         back = back + 1.5_dp*y(1 + 6*i)
      end do
      drag = self%c%s0 + y(chaboche_n_state)
   end subroutine ch_state_outputs

   pure integer function ch_n_props(self) result(n)
      class(chaboche_model), intent(in) :: self
      n = n_props
   end function ch_n_props

   !> E, Poisson, then the constants in their order
   pure function ch_prop_name(self, i) result(name)
      class(chaboche_model), intent(in) :: self
      integer, intent(in) :: i
      character(len=:), allocatable :: name
      select case (i)
      case (1); name = 'E'
      case (2); name = 'Poisson'
      case default; name = trim(chaboche_constant_names(i - 2))
      end select
   end function ch_prop_name

   pure subroutine ch_to_props(self, props)
      class(chaboche_model), intent(in) :: self
      real(dp), intent(out) :: props(:)
      integer :: i
      props(1) = self%youngs
      props(2) = self%poisson
      do i = 1, chaboche_n_constants
         props(2 + i) = chaboche_get_constant(self%c, i)
      end do
   end subroutine ch_to_props

   pure subroutine ch_from_props(self, props, temp, message)
      class(chaboche_model), intent(inout) :: self
      real(dp), intent(in) :: props(:), temp
      character(len=*), intent(out) :: message
      type(error_type), allocatable :: error
      integer :: i
      message = ''
      self%youngs = props(1)
      self%poisson = props(2)
      do i = 1, chaboche_n_constants
         call chaboche_set_constant(self%c, i, props(2 + i))
      end do
      self%temperature = temp
      call chaboche_setup(self, error)
      if (allocated(error)) message = error%message
   end subroutine ch_from_props

   !> State variables: 1-6 inelastic strain, 7-12 and 13-18 the back stresses, 19 R
   pure subroutine ch_fe_layout(self, y_first, code_first, kind)
      class(chaboche_model), intent(in) :: self
      integer, allocatable, intent(out) :: y_first(:), code_first(:), kind(:)
      y_first = [1, 7, 13, 19]
      code_first = [1, 7, 13, 19]
      kind = [block_strain, block_stress, block_stress, block_scalar]
   end subroutine ch_fe_layout

   !> The virgin state is zero, as an FE code starts its state variables
   pure subroutine ch_complete_state(self, y)
      class(chaboche_model), intent(in) :: self
      real(dp), intent(inout) :: y(:)
   end subroutine ch_complete_state
end module usharp_model_chaboche
