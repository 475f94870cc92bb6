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
module usharp_model_chaboche
   use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
   use usharp_kinds, only: dp
   use usharp_error, only: error_type, fatal_error
   use usharp_strings, only: str, lower
   use usharp_model_j2, only: deviator_projector, solve_dense, m_vec
   implicit none
   private

   public :: chaboche_constants, chaboche_model, chaboche_setup
   public :: chaboche_get_constant, chaboche_set_constant, chaboche_constant_index
   public :: chaboche_flow, chaboche_uniaxial_rates, chaboche_update, chaboche_initial_state
   public :: chaboche_moduli

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
   !> publication's range); the recovery constants A_i span decades
   real(dp), parameter, public :: chaboche_literature_low(chaboche_n_constants) = &
      [0.0_dp, 50.0_dp, 2.0_dp, 0.0_dp, 0.5_dp, 1.0e4_dp, 100.0_dp, 1.0e3_dp, 5.0_dp, &
       1.0e-14_dp, 1.0_dp, 1.0e-14_dp, 1.0_dp]
   real(dp), parameter, public :: chaboche_literature_high(chaboche_n_constants) = &
      [150.0_dp, 3000.0_dp, 15.0_dp, 200.0_dp, 50.0_dp, 3.0e5_dp, 3000.0_dp, 5.0e4_dp, 500.0_dp, &
       1.0e-4_dp, 6.0_dp, 1.0e-4_dp, 6.0_dp]
   !> Power of the stress unit in each constant's unit (A_i: 1 - m_i, handled by the caller)
   integer, parameter, public :: chaboche_stress_power(chaboche_n_constants) = &
      [1, 1, 0, 1, 0, 1, 0, 1, 0, 0, 0, 0, 0]
   !> Number of uniaxial and of multiaxial state variables
   integer, parameter, public :: chaboche_n_uniaxial = 2 + chaboche_n_back
   integer, parameter, public :: chaboche_n_state = 7 + 6*chaboche_n_back
   !> Outcome of the update: converged, or the caller must retry with a smaller increment
   integer, parameter, public :: chaboche_ok = 0, chaboche_cut = 1
   !> Backward Euler substeps per increment by default, Newton iterations, halvings
   integer, parameter, public :: chaboche_default_substeps = 8
   integer, parameter :: max_newton = 30, max_halvings = 12

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

   !> A Chaboche model at one temperature
   type :: chaboche_model
      type(chaboche_constants) :: c
      real(dp) :: temperature = 1223.15_dp  !< K (the constants are those at this temperature)
      real(dp) :: youngs = 144000.0_dp      !< Young's modulus, model stress unit
      real(dp) :: poisson = 0.3_dp          !< Poisson's ratio
   end type chaboche_model

contains

   !> Check that the constants are admissible
   pure subroutine chaboche_setup(model, error)
      type(chaboche_model), intent(in) :: model
      type(error_type), allocatable, intent(out) :: error
      integer :: i
      real(dp) :: v
      do i = 1, chaboche_n_constants
         v = chaboche_get_constant(model%c, i)
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
      if (.not. ieee_is_finite(model%youngs) .or. model%youngs <= 0.0_dp) then
         call fatal_error(error, "Young's modulus E must be > 0, got "//str(model%youngs))
      else if (.not. ieee_is_finite(model%poisson) .or. model%poisson <= -1.0_dp &
               .or. model%poisson >= 0.5_dp) then
         call fatal_error(error, "Poisson's ratio must lie in (-1, 0.5), got "//str(model%poisson))
      end if
   end subroutine chaboche_setup

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

   !> Initial state of the uniaxial (n = chaboche_n_uniaxial) or multiaxial form: all zero
   pure function chaboche_initial_state(n) result(y)
      integer, intent(in) :: n
      real(dp) :: y(n)
      y = 0.0_dp
   end function chaboche_initial_state

   !> Shear and bulk moduli from E and Poisson's ratio
   elemental subroutine chaboche_moduli(model, g, k)
      type(chaboche_model), intent(in) :: model
      real(dp), intent(out) :: g, k
      g = model%youngs/(2.0_dp*(1.0_dp + model%poisson))
      k = model%youngs/(3.0_dp*(1.0_dp - 2.0_dp*model%poisson))
   end subroutine chaboche_moduli

   !> Equivalent inelastic strain rate p_dot = <(x - s0 - R)/eta>**n (1/s) at equivalent
   !> effective stress x and isotropic hardening R, and its derivative with respect to the
   !> overstress x - s0 - R
   elemental subroutine chaboche_flow(model, x, r, f, f_o)
      type(chaboche_model), intent(in) :: model
      real(dp), intent(in) :: x, r
      real(dp), intent(out) :: f, f_o
      real(dp) :: z
      z = (x - model%c%s0 - r)/model%c%eta
      if (z <= 0.0_dp) then
         f = 0.0_dp
         f_o = 0.0_dp
      else
         f = exp(model%c%n*log(z))
         f_o = model%c%n*f/(z*model%c%eta)
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
      else if (m == 1.0_dp) then
         h = a
         h_x = 0.0_dp
      else if (x <= 0.0_dp) then
         h = 0.0_dp
         h_x = 0.0_dp
      else
         h = a*exp((m - 1.0_dp)*log(x))
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
         call recovery(model%c%a(i), model%c%m(i), abs(y(1 + i)), h, h_x)
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
         call recovery(model%c%a(i), model%c%m(i), abs(y(1 + i)), h, h_x)
         jac(1 + i, :) = model%c%c(i)*jac(1, :) - model%c%g(i)*y(1 + i)*dp_dy
         ! d(h(|x|) x)/dx = h + h_x |x|
         jac(1 + i, 1 + i) = jac(1 + i, 1 + i) - model%c%g(i)*f - h - h_x*abs(y(1 + i))
      end do
      jac(nr, :) = model%c%b*(model%c%q - y(nr))*dp_dy
      jac(nr, nr) = jac(nr, nr) - model%c%b*f
   end subroutine chaboche_uniaxial_rates

   !> Stress update over one increment. eps0: strain at the start, deps: its increment,
   !> dt: time step (s), y0: state at the start (Mandel). On success status is chaboche_ok;
   !> otherwise y = y0, sigma and ddsde are the elastic trial and status = chaboche_cut asks
   !> the caller for a smaller increment. The increment is integrated in substeps
   !> (chaboche_default_substeps or nsubsteps, doubled while Newton fails); nsub returns how
   !> many were used.
   pure subroutine chaboche_update(model, eps0, deps, dt, y0, sigma, y, ddsde, status, nsub, nsubsteps)
      type(chaboche_model), intent(in) :: model
      real(dp), intent(in) :: eps0(6), deps(6), dt, y0(chaboche_n_state)
      real(dp), intent(out) :: sigma(6), y(chaboche_n_state), ddsde(6, 6)
      integer, intent(out) :: status, nsub
      integer, intent(in), optional :: nsubsteps
      real(dp) :: dyde(chaboche_n_state, 6), ycur(chaboche_n_state), ynew(chaboche_n_state)
      real(dp) :: dydecur(chaboche_n_state, 6), g, k, frac, p(6, 6)
      integer :: level, i, isub, st, base
      logical :: ok

      call chaboche_moduli(model, g, k)
      p = deviator_projector()
      status = chaboche_cut
      base = chaboche_default_substeps
      if (present(nsubsteps)) base = max(1, nsubsteps)
      nsub = 0
      do level = 0, max_halvings
         nsub = base*2**level
         ycur = y0
         dydecur = 0.0_dp
         ok = .true.
         do isub = 1, nsub
            frac = real(isub, dp)/real(nsub, dp)
            call local_newton(model, g, p, eps0 + frac*deps, ycur, dt/nsub, frac, dydecur, &
                              ynew, dyde, st)
            if (st /= chaboche_ok) then
               ok = .false.
               exit
            end if
            ycur = ynew
            dydecur = dyde
         end do
         if (ok) then
            status = chaboche_ok
            exit
         end if
      end do
      if (status /= chaboche_ok) then
         ycur = y0
         dydecur = 0.0_dp
      end if
      y = ycur
      sigma = 2.0_dp*g*(matmul(p, eps0 + deps) - y(1:6)) + k*sum((eps0 + deps)*m_vec)*m_vec
      ddsde = 2.0_dp*g*p + k*spread(m_vec, 1, 6)*spread(m_vec, 2, 6)
      do i = 1, 6
         ddsde(:, i) = ddsde(:, i) - 2.0_dp*g*dydecur(1:6, i)
      end do
   end subroutine chaboche_update

   !> Backward Euler on one subincrement by Newton's method with the analytic Jacobian;
   !> dyde carries the sensitivity of the state to the end strain of the whole increment
   pure subroutine local_newton(model, g, p, eps, yprev, dt, frac, dyde_prev, y, dyde, status)
      type(chaboche_model), intent(in) :: model
      real(dp), intent(in) :: g, p(6, 6), eps(6), yprev(chaboche_n_state), dt, frac
      real(dp), intent(in) :: dyde_prev(chaboche_n_state, 6)
      real(dp), intent(out) :: y(chaboche_n_state), dyde(chaboche_n_state, 6)
      integer, intent(out) :: status
      real(dp) :: r(chaboche_n_state), jac(chaboche_n_state, chaboche_n_state)
      real(dp) :: drde(chaboche_n_state, 6), dy(chaboche_n_state, 1), tol_strain, tol_stress
      integer :: it, info, ns
      ns = chaboche_n_state
      status = chaboche_cut
      y = yprev
      tol_strain = 1.0e-13_dp + 1.0e-11_dp*maxval(abs(yprev(1:6)))
      tol_stress = 1.0e-11_dp*max(maxval(abs(yprev(7:ns))), 1.0e-3_dp*model%youngs)
      do it = 1, max_newton
         call residual(model, g, p, eps, yprev, dt, y, r, jac, drde)
         if (.not. all(ieee_is_finite(r)) .or. .not. all(ieee_is_finite(jac))) return
         dy(:, 1) = -r
         call solve_dense(jac, dy, info)
         if (info /= 0 .or. .not. all(ieee_is_finite(dy))) return
         y = y + dy(:, 1)
         if (maxval(abs(dy(1:6, 1))) <= tol_strain .and. maxval(abs(dy(7:ns, 1))) <= tol_stress) then
            call residual(model, g, p, eps, yprev, dt, y, r, jac, drde)
            dyde = dyde_prev - frac*drde
            call solve_dense(jac, dyde, info)
            if (info /= 0 .or. .not. all(ieee_is_finite(dyde))) return
            status = chaboche_ok
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
         call recovery(model%c%a(i), model%c%m(i), ji, h, h_x)
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
end module usharp_model_chaboche
