!> What the effects of `usharp diagnose` (usharp_effects) set for one test's simulation:
!> their parameters, all zero for the plain model. Below the model interface, which says how
!> they act on a model (model_type's extended_rates and extended_initial).
!>
!> Units: stresses in the model's unit, times in s, temperatures in K.
module usharp_effect_values
   use usharp_kinds, only: dp
   implicit none
   private

   public :: test_effects

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
   end type test_effects
end module usharp_effect_values
