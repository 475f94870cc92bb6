!> Effects a model leaves out, for `usharp diagnose`: each is a documented extension
!> of the simulation or of the measurement with its own parameters, and each is neutral when
!> its parameters are zero. test_effects holds what one test's simulation sees; the catalogue
!> names the effects, their parameters (global or one per test) and their scales.
!>
!> Units: stresses in the model's unit, times in s, temperatures in K.
module usharp_effects
   use usharp_kinds, only: dp
   use usharp_math, only: exp_dp, cubic_piece
   use usharp_error, only: error_type
   use usharp_model, only: model_type, wrapped_rates
   use usharp_effect_values, only: test_effects
   implicit none
   private

   public :: test_effects, effect_info, n_effects, effect_catalogue, effect_index
   public :: effects_of, extended_rates, n_extended, lagged_value, lag_corners, effect_nparams
   public :: effect_acts, effect_acts_why
   public :: param_global, param_per_test, effect_model, extended_size, extended_initial
   public :: wrapped_rates, states_act

   !> States of the extended Miller model: eps_in, R, D, accumulated inelastic strain p, R2;
   !> of any other model its own states, then p and R2
   integer, parameter :: n_extended = 5
   !> How an effect's parameter is shared: one value for all tests, or one per test
   integer, parameter :: param_global = 1, param_per_test = 2
   !> Number of effects in the catalogue
   integer, parameter :: n_effects = 10

   !> One catalogue entry
   type :: effect_info
      character(len=16) :: name = ''
      character(len=96) :: what = ''
      integer :: nparam = 0                  !< parameters per group (global or per test)
      integer :: sharing = param_global
      character(len=12) :: pname(2) = ''
      character(len=12) :: punit(2) = ''
      real(dp) :: scale(2) = 1.0_dp          !< unit of the search variable (step 1e-3 of it)
      logical :: nonneg(2) = .false.         !< parameter kept >= 0
      logical :: screened(2) = .true.        !< has a gradient at zero (used in screening)
      !> Largest magnitude the effect can physically have; a fit beyond it stands for
      !> something else (huge: no limit)
      real(dp) :: plausible(2) = huge(1.0_dp)
      !> Low end of the magnitude a rig or specimen realistically shows (0: a rate held at its
      !> default, not varied); for backstress2 of the saturation H3/gamma3, for drift of the
      !> strain it adds over a test
      real(dp) :: low(2) = 0.0_dp
      character(len=40) :: low_what = ''     !< the low end in words
      !> Half-width of each parameter's search box, in units of its scale (a nonneg one
      !> searched in [0, box])
      real(dp) :: box(2) = 1.0e3_dp
      !> Acts through the extended model's own states, the accumulated inelastic strain p and
      !> the second back stress R2 (the other effects leave them at rest)
      logical :: states = .false.
   end type effect_info

contains

   !> The catalogue. Scales are in the model's units where a stress enters (peak: a typical
   !> stress of the data, model unit).
   pure function effect_catalogue(peak) result(cat)
      real(dp), intent(in) :: peak
      type(effect_info) :: cat(n_effects)
      cat(1) = effect_info('compliance', 'load-train/extensometer compliance: measured strain '// &
         'includes kappa*sigma/E', 1, param_global, ['kappa       ', '            '], &
         ['-           ', '            '], [1.0_dp, 1.0_dp], [.false., .false.], [.true., .true.], [0.5_dp, 0.0_dp])
      cat(2) = effect_info('lag', 'control tracking error: applied value lags the command, '// &
         'first order, time constant tau', 1, param_global, ['tau         ', '            '], &
         ['s           ', '            '], [1.0_dp, 1.0_dp], [.true., .false.], [.true., .true.], [2.0_dp, 0.0_dp])
      cat(3) = effect_info('temperature', 'temperature offset per test: theta(T+dT) and '// &
         'E(T+dT)', 1, param_per_test, ['dT          ', '            '], &
         ['K           ', '            '], [10.0_dp, 1.0_dp], [.false., .false.], [.true., .true.], [25.0_dp, 0.0_dp])
      cat(4) = effect_info('scatter', 'specimen-to-specimen scatter: per-test factors on E '// &
         'and on the initial drag stress', 2, param_per_test, ['dE/E        ', 'dD0/D0      '], &
         ['-           ', '-           '], [1.0_dp, 1.0_dp], [.false., .false.], [.true., .true.], [0.2_dp, 0.4_dp])
      cat(5) = effect_info('initial', 'initial state other than virgin: back stress R0 and '// &
         'drag offset dD0', 2, param_global, ['R0          ', 'dD0         '], &
         ['stress      ', 'stress      '], [peak, peak], [.false., .false.], &
         [.true., .true.], [0.5_dp*peak, 0.5_dp*peak])
      cat(6) = effect_info('shift', 'time offset: the stress channel lags the strain '// &
         'channel by delta', 1, param_global, ['delta       ', '            '], &
         ['s           ', '            '], [1.0_dp, 1.0_dp], [.false., .false.], [.true., .true.], [5.0_dp, 0.0_dp])
      ! Cyclic softening saturates (a drag that fell without end would reach zero): over
      ! p << 1/b the form is D*(1 - a*b*p), a softening that has not yet saturated. The rate
      ! b has no gradient at a = 0: screening holds it (usharp_diagnose_numerics)
      cat(7) = effect_info('softening', 'saturating cyclic softening: flow-law drag '// &
         'D*(1 - a*(1 - exp(-b*p))), p inelastic strain', 2, param_global, &
         ['a           ', 'b           '], ['-           ', '-           '], [0.1_dp, 100.0_dp], &
         [.false., .true.], [.true., .false.], [0.5_dp, huge(1.0_dp)])
      cat(8) = effect_info('backstress2', 'second back stress of faster rate: '// &
         'dR2 = H3 deps_in - gamma3 R2 |deps_in|', 2, param_global, ['H3          ', &
         'gamma3      '], ['stress      ', '-           '], [peak, 1000.0_dp], &
         [.true., .true.], [.true., .false.], [huge(1.0_dp), huge(1.0_dp)])
      ! A drift of 1e-5/s moves a 100 s test's strain by 0.1 %: beyond what a rig that drifts
      ! (air cooling of an extensometer's arms) shows in one test
      cat(9) = effect_info('drift', 'extensometer drift per test: measured strain = '// &
         'specimen strain + d*(t - t0)', 1, param_per_test, ['d           ', '            '], &
         ['1/s         ', '            '], [1.0e-6_dp, 1.0_dp], [.false., .false.], [.true., .true.], &
         [1.0e-5_dp, 0.0_dp])
      ! One per test: each specimen has its own cross-section. E is the deck's, never a
      ! fitted constant, so each test's elastic slope shows its gain, one that every test
      ! shares too. A tenth is a diameter 5 % off or a load cell far out of calibration
      cat(10) = effect_info('gain', 'stress-channel gain per test (load-cell calibration, '// &
         'cross-section area): measured stress = (1 + g) sigma', 1, param_per_test, &
         ['g           ', '            '], ['-           ', '            '], [1.0_dp, 1.0_dp], &
         [.false., .false.], [.true., .true.], [0.1_dp, 0.0_dp])
      ! The low ends of the ranges the diagnosis is validated over (docs/validation.md): a
      ! modulus 3 % off, a lag or delay of 0.1 s, 5 K, a modulus 2 % and a drag 3 % off per
      ! specimen, an initial back stress or drag 2 % of the peak, a softening of 5 %, a second
      ! back stress saturating at 4 % of the peak, a drift of 2e-5 strain over a test, a
      ! stress channel reading 2 % off
      cat(1)%low = [0.03_dp, 0.0_dp]
      cat(1)%low_what = 'kappa 0.03'
      cat(2)%low = [0.1_dp, 0.0_dp]
      cat(2)%low_what = 'tau 0.1 s'
      cat(3)%low = [5.0_dp, 0.0_dp]
      cat(3)%low_what = 'dT 5 K per test'
      cat(4)%low = [0.02_dp, 0.03_dp]
      cat(4)%low_what = 'dE/E 0.02 or dD0/D0 0.03 per test'
      cat(5)%low = [0.02_dp*peak, 0.02_dp*peak]
      cat(5)%low_what = 'R0 or dD0 2 % of the peak'
      cat(6)%low = [0.1_dp, 0.0_dp]
      cat(6)%low_what = 'delta 0.1 s'
      cat(7)%low = [0.05_dp, 0.0_dp]
      cat(7)%low_what = 'a 0.05 at b 100'
      cat(8)%low = [0.04_dp*peak, 0.0_dp]
      cat(8)%low_what = 'H3/gamma3 4 % of the peak'
      cat(9)%low = [2.0e-5_dp, 0.0_dp]
      cat(9)%low_what = '2e-5 strain over a test'
      cat(10)%low = [0.02_dp, 0.0_dp]
      cat(10)%low_what = 'g 0.02 per test'
      ! (1 + g) > 0: a gain beyond a half stands for nothing a rig shows
      cat(10)%box = [0.5_dp, 0.5_dp]
      ! The second back stress's magnitude is its saturation H3/gamma3: H3's box reaches the
      ! peak's saturation at gamma3's box end (1e6). At 1000 times the peak it capped the
      ! saturation at 0.1 of the peak for gamma3 = 1e4 and 0.2 for 5000, below Alloy 617's
      ! fast back stress (0.26 of the peak at gamma3 4200): refits ran to that end and only
      ! a start near gamma3 = 4000 came close (objective 240.9 there, 360.8 from 1e4)
      ! (H3's unit is the peak: its box is gamma3's largest value, 1e6)
      cat(8)%box(1) = cat(8)%box(2)*cat(8)%scale(2)
      cat(7)%states = .true.
      cat(8)%states = .true.
   end function effect_catalogue

   !> Catalogue index of an effect by name, 0 when there is none
   pure integer function effect_index(name) result(k)
      character(len=*), intent(in) :: name
      type(effect_info) :: cat(n_effects)
      integer :: i
      cat = effect_catalogue(1.0_dp)
      k = 0
      do i = 1, n_effects
         if (trim(cat(i)%name) == trim(adjustl(name))) k = i
      end do
   end function effect_index

   !> Whether effect k (parameter group g when given) acts on model: the effects on states of
   !> the model's own (an initial back stress and drag, specimen scatter's factor on the
   !> initial drag, a softened drag) where the model applies them (own_state_effects), a
   !> temperature offset where its rates follow the temperature (temperature_matters); the
   !> others act on every model through the wrapped rates, the control and the measurement
   pure logical function effect_acts(model, k, g) result(acts)
      class(model_type), intent(in) :: model
      integer, intent(in) :: k
      integer, intent(in), optional :: g
      select case (k)
      case (3)
         acts = model%temperature_matters()
      case (4)
         acts = .true.
         if (present(g)) acts = g == 1 .or. model%own_state_effects()
      case (5, 7)
         acts = model%own_state_effects()
      case default
         acts = .true.
      end select
   end function effect_acts

   !> Why effect k does not act on model (see effect_acts), in words
   function effect_acts_why(model, k) result(text)
      class(model_type), intent(in) :: model
      integer, intent(in) :: k
      character(len=:), allocatable :: text
      if (k == 3) then
         text = 'the '//model%name()//' model''s rates do not follow the temperature'
      else
         text = 'it acts on a back stress or drag stress state that the '//model%name()// &
                ' model does not give the diagnosis'
      end if
   end function effect_acts_why

   !> Number of parameters of effect k for ntests tests
   pure integer function effect_nparams(info, ntests) result(np)
      type(effect_info), intent(in) :: info
      integer, intent(in) :: ntests
      np = info%nparam
      if (info%sharing == param_per_test) np = np*ntests
   end function effect_nparams

   !> Per-test effects of effect k with parameters p (in physical units; per-test effects
   !> ordered parameter-major: all tests' first parameter, then the second); eff_base holds
   !> what is set regardless (dlnE_dT, the fixed gamma3 of screening)
   pure function effects_of(k, p, ntests, eff_base) result(eff)
      integer, intent(in) :: k, ntests
      real(dp), intent(in) :: p(:)
      type(test_effects), intent(in) :: eff_base
      type(test_effects) :: eff(ntests)
      integer :: i
      eff = eff_base
      select case (k)
      case (1)
         eff%compliance = p(1)
      case (2)
         eff%lag = p(1)
      case (3)
         do i = 1, ntests
            eff(i)%dtemp = p(i)
         end do
      case (4)
         do i = 1, ntests
            eff(i)%modulus = p(i)
            eff(i)%strength = p(ntests + i)
         end do
      case (5)
         eff%r0 = p(1)
         eff%dd0 = p(2)
      case (6)
         eff%shift = p(1)
      case (7)
         eff%soften = p(1)
         if (size(p) > 1) eff%soften_rate = p(2)
      case (8)
         eff%h3 = p(1)
         if (size(p) > 1) eff%gamma3 = p(2)
      case (9)
         do i = 1, ntests
            eff(i)%drift = p(i)
         end do
      case (10)
         do i = 1, ntests
            eff(i)%gain = p(i)
         end do
      end select
   end function effects_of

   !> The model a test with effects eff sees: modulus E*(1 + dE/E)*(1 + dlnE_dT*dT), set up at
   !> the nominal temperature, then moved to T + dT by set_temperature: what the rates take
   !> from temperature follows (Miller: B*theta), the initial state stays that of the nominal
   !> temperature (Miller's D0: the virgin material's drag is a state of the specimen, not of
   !> the thermocouple's reading; D0 from the yield stress at T + dT would keep a hotter test
   !> exactly as strong at the reference rate, and make an offset shared by every test a mere
   !> factor on B that the constants take up). The nominal temperature is the test's own when
   !> given, else the model's.
   subroutine effect_model(model, eff, out, error, temperature)
      class(model_type), intent(in) :: model
      type(test_effects), intent(in) :: eff
      class(model_type), allocatable, intent(out) :: out
      type(error_type), allocatable, intent(out) :: error
      !> K, the test's own temperature (when > 0) in place of the model's
      real(dp), intent(in), optional :: temperature
      allocate (out, source=model)
      if (present(temperature)) then
         if (temperature > 0.0_dp) out%temperature = temperature
      end if
      out%youngs = model%youngs*(1.0_dp + eff%modulus)*(1.0_dp + eff%dlnE_dT*eff%dtemp)
      call out%setup(error)
      if (allocated(error)) return
      call out%set_temperature(out%temperature + eff%dtemp, error)
   end subroutine effect_model

   !> Whether the extended model's own states act in eff: p through a softening, R2 through a
   !> second back stress (without them p only accumulates and R2 stays 0)
   elemental logical function states_act(eff)
      type(test_effects), intent(in) :: eff
      states_act = eff%soften /= 0.0_dp .or. eff%h3 /= 0.0_dp
   end function states_act

   !> Number of states of the extended model
   pure integer function extended_size(model) result(n)
      class(model_type), intent(in) :: model
      n = model%n_uniaxial() + 2
   end function extended_size

   !> Start of the extended state (the model's extended_initial): its virgin state, for the
   !> Miller model with the initial back stress R0 and the drag D0*(1 + dD0/D0) + dD0; p = R2 = 0
   pure subroutine extended_initial(model, eff, y)
      class(model_type), intent(in) :: model
      type(test_effects), intent(in) :: eff
      real(dp), intent(out) :: y(:)
      call model%extended_initial(eff, y)
   end subroutine extended_initial

   !> Value of a control seen through a first-order lag of time constant tau (s), starting at
   !> rest on vc(1), at time t in piece k; yk(k) holds the lagged value at corner k (from
   !> lag_corners). The control is piecewise linear between the corners (tc, vc), or with mc
   !> (second derivatives at the corners) the cubic spline through them (a smooth forcing,
   !> followed on its knots). On a piece the lag solves to y = yp + (y_k - yp(t_k))
   !> exp(-(t - t_k)/tau) with yp = u - tau u' + tau**2 u'' - tau**3 u''' (u its control),
   !> for a linear piece of slope s yp = u - s tau.
   pure subroutine lagged_value(tc, vc, yk, k, tau, t, y, ydot, mc)
      real(dp), intent(in) :: tc(:), vc(:), yk(:), tau, t
      integer, intent(in) :: k
      real(dp), intent(out) :: y, ydot
      real(dp), intent(in), optional :: mc(:)
      real(dp) :: s, u, e, u1, u2, u3, p0, p1, ypk
      if (present(mc)) then
         call cubic_piece(tc, vc, mc, k, t, u, u1, u2, u3)
         if (tau <= 0.0_dp) then
            y = u
            ydot = u1
            return
         end if
         ! yp at t and at the piece's start (where u = vc(k))
         p0 = u - tau*(u1 - tau*(u2 - tau*u3))
         p1 = u1 - tau*(u2 - tau*u3)
         call cubic_piece(tc, vc, mc, k, tc(k), u, u1, u2)
         ypk = u - tau*(u1 - tau*(u2 - tau*u3))
         e = exp_dp(-(t - tc(k))/tau)
         y = p0 + (yk(k) - ypk)*e
         ydot = p1 - (yk(k) - ypk)*e/tau
         return
      end if
      s = (vc(k + 1) - vc(k))/(tc(k + 1) - tc(k))
      u = vc(k) + s*(t - tc(k))
      if (tau <= 0.0_dp) then
         y = u
         ydot = s
         return
      end if
      e = exp_dp(-(t - tc(k))/tau)
      y = u - s*tau + (yk(k) - vc(k) + s*tau)*e
      ydot = s - (yk(k) - vc(k) + s*tau)*e/tau
   end subroutine lagged_value

   !> Lagged control value at every corner (first-order lag, time constant tau s, at rest on
   !> the first value); with tau = 0 the corners themselves. With mc, of the cubic spline
   !> through the corners with second derivatives mc (see lagged_value).
   pure function lag_corners(tc, vc, tau, mc) result(yk)
      real(dp), intent(in) :: tc(:), vc(:), tau
      real(dp), intent(in), optional :: mc(:)
      real(dp) :: yk(size(tc))
      real(dp) :: rate
      integer :: k
      yk(1) = vc(1)
      do k = 1, size(tc) - 1
         call lagged_value(tc, vc, yk, k, tau, tc(k + 1), yk(k + 1), rate, mc)
      end do
   end function lag_corners

   !> Rates of the extended state (the model's states, then p and R2) at stress sigma, as the
   !> model's extended_rates says: any model's rates driven by sigma - R2, with
   !> dp/dt = |deps_in/dt| and dR2/dt = H3 deps_in/dt - gamma3 R2 dp/dt; the Miller model's
   !> with its drag softened in the flow law too. With jac, also jac(i, j) = d ydot_i / d y_j,
   !> sigma depending on eps_in through dsig_depsin (the values are the same bit for bit with
   !> and without it).
   pure subroutine extended_rates(model, eff, sigma, y, ydot, dsig_depsin, jac)
      class(model_type), intent(in) :: model
      type(test_effects), intent(in) :: eff
      real(dp), intent(in) :: sigma
      real(dp), intent(in), contiguous :: y(:)
      real(dp), intent(out), contiguous :: ydot(:)
      real(dp), intent(in), optional :: dsig_depsin
      real(dp), intent(out), optional, contiguous :: jac(:, :)
      call model%extended_rates(eff, sigma, y, ydot, dsig_depsin, jac)
   end subroutine extended_rates

end module usharp_effects
