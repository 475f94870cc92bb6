!> What the effects of `usharp diagnose` (usharp_effects) set for one test's simulation:
!> their parameters, all zero for the plain model. Below the model interface, which says how
!> they act on a model (model_type's extended_rates and extended_initial).
!>
!> Units: stresses in the model's unit, times in s, temperatures in K.
module usharp_effect_values
   use usharp_kinds, only: dp
   implicit none
   private

   public :: test_effects, effect_reals

   !> What one test's simulation sees (all zero: the plain model)
   type :: test_effects
      real(dp) :: compliance = 0.0_dp  !< kappa: machine strain kappa*sigma/E in the measured strain (-)
      real(dp) :: lag = 0.0_dp         !< s, first-order lag of the applied control value
      real(dp) :: dtemp = 0.0_dp       !< K, offset of the test temperature
      real(dp) :: dlnE_dT = 0.0_dp     !< 1/K, d ln E / dT used with dtemp
      real(dp) :: modulus = 0.0_dp     !< relative change of E (specimen scatter)
      real(dp) :: strength = 0.0_dp    !< relative change of D0 (specimen scatter)
      real(dp) :: r0 = 0.0_dp          !< initial back stress, model unit
      real(dp) :: dd0 = 0.0_dp         !< offset of the initial drag stress, model unit
      real(dp) :: shift = 0.0_dp       !< s, the stress channel lags the strain channel
      !> -, cyclic softening: drag in the flow law D*(1 - soften*(1 - exp(-soften_rate*p))),
      !> saturating at the share soften (negative: hardening)
      real(dp) :: soften = 0.0_dp
      real(dp) :: soften_rate = 0.0_dp !< -, its rate: 1/(accumulated inelastic strain to 63 %)
      real(dp) :: h3 = 0.0_dp          !< model unit, modulus of the second back stress
      real(dp) :: gamma3 = 0.0_dp      !< -, its dynamic recovery: dR2 = H3 deps_in - gamma3 R2 dp
      !> 1/s, extensometer drift: the measured strain is the specimen's plus drift*(t - t0), t0
      !> the test's start (a strain-controlled specimen sees the command less the drift)
      real(dp) :: drift = 0.0_dp
      !> -, stress-channel gain: the measured stress is (1 + gain) times the specimen's (a
      !> load cell's calibration, a cross-section measured wrong); a stress-controlled
      !> specimen so sees the command divided by 1 + gain
      real(dp) :: gain = 0.0_dp
   end type test_effects

contains

   !> The values of e, in order, component by component: a copy of the whole type would take
   !> the padding bytes of any component that is not real(dp) into a key, whose values no
   !> run fixes (the key of one problem then differed between a run and its resumption)
   pure function effect_reals(e) result(v)
      type(test_effects), intent(in) :: e
      real(dp), allocatable :: v(:)
      v = [e%compliance, e%lag, e%dtemp, e%dlnE_dT, e%modulus, e%strength, e%r0, e%dd0, e%shift, &
           e%soften, e%soften_rate, e%h3, e%gamma3, e%drift, e%gain]
   end function effect_reals
end module usharp_effect_values
