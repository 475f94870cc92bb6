!> What a diagnosis works on and what it finds: the problem shared by its steps (tests, fit
!> and held-out sets, noise), each effect's outcome, and the whole result
module usharp_diagnose_types
   use, intrinsic :: iso_fortran_env, only: int64
   use usharp_kinds, only: dp
   use usharp_math, only: log_dp
   use usharp_strings, only: real_str, interval_format, interval_end, report_line_len
   use usharp_objective, only: fit_problem
   use usharp_input_test, only: name_len
   use usharp_effects, only: test_effects, effect_info
   use usharp_regions, only: region_stat
   use usharp_diagnose_options, only: diagnose_options, bic_margin
   use usharp_diagnose_journal, only: diagnose_journal
   use usharp_diagnose_memo, only: run_memo
   implicit none
   private

   public :: params_bound_note, hardening_note, side_word
   public :: diagnose_context, physical_point, effect_outcome, diagnose_result, fit_structured, held_quiet
   public :: diagnose_progress, tell, separation_type, n_candidates, leaves_noise, explains_most, hidden_effect, magnitude_text, &
             interval_text, &
             hidden_size
   public :: explains_resolved, rest_at_noise, gap_fit_ref, unit_text, bound_list, per_test_ref
   public :: deviance_change, prediction_open, open_spread, separating_d
   public :: step_cost, step_done, joint_wanted, named_effect, fit_effects_shown, bic_only, &
             joint_decides, fit_gap_left, rest_wanted, held_fit_only, form_left_open, form_beats_leader, &
             partial_carry, held_rest_open, joint_reason, fit_effect_not_carried, baseline_left_behind, form_open

   !> An effect "explains" the gap when it removes at least this share of the structured
   !> gap on the fit tests and on the held-out tests (else it "partly explains" it); the
   !> self-check asks the same of the held-out gap
   real(dp), parameter, public :: most = 0.8_dp
   !> Below this share of each structured gap a leader "explains little of the gap"
   real(dp), parameter, public :: little = 0.3_dp

   !> A delay below the sampling interval is measured by the data when its 95 % interval
   !> lies within this share of it on either side (about 8 standard errors from zero: a
   !> shift that lowered BIC by 13 on clean data is some 4)
   real(dp), parameter, public :: delay_precision = 0.25_dp

   !> Candidate tests of the separation step
   integer, parameter :: n_candidates = 5
   !> Shares of the held-out gap at least this far apart, at end points of a refit that the
   !> fit tests cannot tell apart, leave its prediction open
   real(dp), parameter :: open_spread = 0.05_dp
   !> An expected chi-square difference at which a candidate test tells two responses apart:
   !> one degree of freedom at 99.9 %
   real(dp), parameter :: separating_d = 10.83_dp

   !> Which candidate test separates two effects that explain the gap equally well
   type :: separation_type
      integer :: a = 0, b = 0                  !< indices into the result's effects
      character(len=80) :: names(n_candidates) = ''
      real(dp) :: d(n_candidates) = 0.0_dp     !< expected discrimination (chi-square) per candidate
      integer :: best = 0                      !< the candidate with the largest d
   end type separation_type

   abstract interface
      !> Told at each step of a diagnosis: what it is doing, simulations so far, elapsed s
      subroutine diagnose_progress(stage, nevals, seconds)
         import :: dp
         character(len=*), intent(in) :: stage
         integer, intent(in) :: nevals
         real(dp), intent(in) :: seconds
      end subroutine diagnose_progress
   end interface

   !> What one step of a diagnosis cost: simulations of the test set (deterministic) and
   !> time (for the log only)
   type :: step_cost
      character(len=128) :: name = ''
      integer :: nevals = 0
      real(dp) :: wall = 0.0_dp             !< s, elapsed
      real(dp) :: cpu = 0.0_dp              !< s, processor time of every thread
   end type step_cost

   !> What of an effect the tests could miss: above `times` its low end the significance
   !> rule finds it with power 0.95 (below, it may hide), and the candidate test that would
   !> find that much of it
   type :: hidden_effect
      real(dp) :: times = -1.0_dp            !< multiple of the low end (negative: not computed)
      !> that magnitude as a parameter value ('' when it is not one number)
      character(len=64) :: magnitude = ''
      character(len=80) :: test = ''         !< the candidate ('' when none simulates)
      real(dp) :: power = -1.0_dp            !< its power there
      !> that multiple lies beyond the effect's physical limit (see hidden_size)
      logical :: beyond = .false.
   end type hidden_effect

   !> A search point of a refit (its problem's coordinates: constants and the effect's parameters)
   type :: end_point
      real(dp), allocatable :: x(:)
   end type end_point

   !> A refit's end point in physical units, which a problem of another set of tests can
   !> start from: the fitted constants and every effect parameter of every test
   type :: physical_point
      real(dp), allocatable :: c(:), p(:)
   end type physical_point

   !> The problem every step of a diagnosis works on
   type :: diagnose_context
      type(fit_problem) :: prob              !< all tests; constants: the baseline's once fitted
      integer, allocatable :: ifit(:)        !< tests fitted
      integer, allocatable :: ihold(:)       !< tests held out
      type(diagnose_options) :: opts
      type(test_effects) :: eff_base         !< dlnE_dT, gamma3
      real(dp) :: peak = 0.0_dp              !< largest |response| of any test
      real(dp) :: h = 0.0_dp                 !< forward-difference step of the fit (log10 units)
      real(dp), allocatable :: nv(:)         !< noise variance of each weighted residual, all tests
      real(dp), allocatable :: noise(:)      !< each test's noise sd (response unit, residual_noise)
      type(effect_info), allocatable :: cat(:)  !< the catalogue scaled to peak
      !> Told of each step (null: nobody listens)
      procedure(diagnose_progress), pointer, nopass :: progress => null()
      integer(int64) :: clock0 = 0           !< system clock at the start
      !> The journal its units are kept in and replayed from (null: none)
      type(diagnose_journal), pointer :: journal => null()
      !> The Levenberg-Marquardt runs made so far (null: each run is made)
      type(run_memo), pointer :: memo => null()
      !> The end point of each catalogue effect's refit against an earlier baseline (see
      !> rebaseline in usharp_diagnose; x unallocated: none): a further start of its refit
      !> against this one where that refit has the same free parameters (not where one of
      !> them held the effect's rate), so that a better baseline does not leave it above an
      !> end point found before
      type(end_point), allocatable :: earlier(:)
      !> The end point of each catalogue effect's refit on the fit tests, with its values
      !> fitted to the held-out tests (see joint_stage in usharp_diagnose; c unallocated:
      !> none): its refit with every test fitted goes on from there where it is clearly
      !> lower (see from_carried in usharp_diagnose_refit). That stage's baseline has taken
      !> up what an effect shared by all tests can hide in the constants (a temperature
      !> offset of 17 K, refitted from there to 39.7 % of the gap where the fit tests' own
      !> refit, taken on, removes it all)
      type(physical_point), allocatable :: carried(:)
   end type diagnose_context

   !> One effect: screening, and the refit when it led
   type :: effect_outcome
      integer :: k = 0
      character(len=16) :: name = ''
      integer :: q = 0                       !< free parameters in the fit
      real(dp) :: pred_drop = 0.0_dp         !< screening: predicted fall of the objective
      real(dp) :: pred_dbic = 0.0_dp         !< screening: predicted BIC change (negative: better)
      !> Expected chi-square of the effect at the low end of its range on the fit tests,
      !> beyond what the constants take up, and the power of the BIC rule against it
      !> (negative: not computed)
      real(dp) :: lambda_low = 0.0_dp, power_low = -1.0_dp
      type(hidden_effect) :: hidden
      logical :: refitted = .false.
      real(dp) :: f_after = 0.0_dp
      real(dp), allocatable :: per_test_after(:)
      real(dp), allocatable :: p(:), p_lo(:), p_hi(:)  !< fitted parameters, 95 % interval
      real(dp), allocatable :: p_all(:)      !< every parameter, all tests (held-out ones fitted)
      logical, allocatable :: p_acts(:)     !< which of p_all act on the model (effect_acts)
      !> Its parameters of the held-out tests were fitted to them (an effect per test), not
      !> predicted: how well it meets them is no prediction
      logical :: held_fitted = .false.
      logical, allocatable :: p_profiled(:)  !< that interval from the profile likelihood
      logical, allocatable :: p_lo_open(:), p_hi_open(:)  !< a profile's end the data do not bound
      real(dp), allocatable :: x(:)          !< search point after screening
      real(dp), allocatable :: x_alt(:, :)   !< end points of its other screening starts, best first
      !> parameter names, a per-test one with its test's name, and their units (the
      !> catalogue's: 'stress' for the model's stress unit, '-' for none)
      character(len=name_len + 17), allocatable :: pname(:)
      character(len=12), allocatable :: punit(:)
      integer, allocatable :: p_test(:)      !< each one's test (a per-test parameter; 0: global)
      real(dp), allocatable :: c(:)          !< constants of the refit
      !> the initial drag stress of the model at those constants (model stress unit; what an
      !> initial effect's dD0 adds to and a scatter's dD0/D0 scales), negative when none
      real(dp) :: drag0 = -1.0_dp
      real(dp), allocatable :: x_fit(:)      !< search point at the end of the refit
      !> End points of the refit's starts (columns) and their objectives on the fit tests
      real(dp), allocatable :: x_ends(:, :), f_ends(:)
      !> Other end points of the refit that the fit tests cannot tell from its own (BIC within
      !> bic_margin), and the least and most of the held-out gap they carry
      integer :: n_alike = 0
      real(dp) :: shrink_alike_lo = 0.0_dp, shrink_alike_hi = 0.0_dp
      !> The held-out gap the refit's own end point leaves, and its share removed; with end
      !> points alike (n_alike > 0) held_gap and shrink_held are those of their prediction
      !> weighted by their evidence (see held_alike)
      real(dp) :: held_gap_point = 0.0_dp, shrink_held_point = 0.0_dp
      !> The two of those end points (its own among them) that carry the least and the most
      !> of the held-out gap: their constants (columns 1 and 2, as c) and every parameter (as
      !> p_all), for the test that would tell them apart (see prediction_open)
      real(dp), allocatable :: c_open(:, :), p_open(:, :)
      integer, allocatable :: c_bound(:)     !< its constants at a search bound (see bound_list)
      real(dp) :: daic = 0.0_dp, dbic = 0.0_dp
      !> A per-test effect's BIC counts the parameters of the tests that show it (see
      !> count_shown in usharp_diagnose_refit): q_bic of q (-1: not computed), the Wald
      !> chi-square of the groups left out (the deviance they take away), the names of the
      !> tests counted, and dBIC with every test's parameters counted
      integer :: q_bic = -1
      real(dp) :: wald_dropped = 0.0_dp, dbic_all = 0.0_dp
      character(len=:), allocatable :: shown_on
      !> Which of its free parameters (as p) BIC counts: all but a per-test effect's values of
      !> the tests that do not show it
      logical, allocatable :: p_counted(:)
      real(dp) :: held_gap = 0.0_dp          !< structured gap of the held-out tests with it
      real(dp) :: shrink_fit = 0.0_dp, shrink_held = 0.0_dp
      real(dp) :: gap_fit_after = 0.0_dp  !< the fit tests' structured gap left with the effect
      !> The held-out gap the refit's constants remove with the effect off: where they alone
      !> leave none above its floor, their prediction is no evidence of the effect
      real(dp) :: shrink_held_constants = -huge(1.0_dp)
      !> Each test's objective at the refit's constants with the effect off (unallocated
      !> where they fail): well below the reference baseline's on the fit tests (see
      !> baseline_left_behind), the constants alone fit better, and it was not the optimum
      real(dp), allocatable :: per_constants(:)
      logical :: carried_by_constants = .false.
      logical :: significant = .false., confirmed = .false.
      logical :: plausible = .true.          !< every magnitude within the effect's physical limit
      !> Refitted with its rate (the second back stress's gamma3, the softening's b) held at
      !> its screening start's value (rate_start): free, the fit tests left the rate undetermined and the
      !> magnitude beyond its limit (see refit)
      logical :: held = .false.
      real(dp) :: rate_lo = 0.0_dp, rate_hi = 0.0_dp  !< the rate's interval when free
      !> Why the rate was held: rate_open or rate_at_end (see rate_doubt)
      integer :: rate_why = 0
      !> The rate (see held_rate) of the screening start whose end point led (0: the
      !> screening's own), and of each x_alt column's start; a refit that holds the rate
      !> holds it at its start's (see rate_rungs)
      real(dp) :: rate_start = 0.0_dp
      real(dp), allocatable :: rate_alt(:)
      !> Of its free parameters, those at a search bound (their intervals do not hold)
      integer, allocatable :: p_bound(:)
      real(dp) :: worst = 0.0_dp             !< largest |parameter|/limit of the fit tests
      character(len=64) :: worst_what = ''   !< which magnitude that is
      !> The largest of a per-test effect's values fitted to the held-out tests against its
      !> limit, and which (parameter and test): reported, not judged (see judge_held_values)
      real(dp) :: worst_held = 0.0_dp
      character(len=:), allocatable :: worst_held_what
      !> A delay (shift, lag) resolved by the data: not below their sampling interval
      logical :: resolved = .true.
      !> A delay below the sampling interval that the data measure all the same: its 95 %
      !> interval within delay_precision of it (see judge)
      logical :: measured = .false.
      logical, allocatable :: worse(:)       !< fit tests it makes worse beyond their noise
      !> Objectives of the refit from its further starts (the best is kept): the spread
      real(dp) :: f_lo = 0.0_dp, f_hi = 0.0_dp
      !> The refit's objective before its profile met a lower point and it was refitted from
      !> there (0: it was not)
      real(dp) :: f_unprofiled = 0.0_dp
      !> The lowest objective the walks of its last profile met (its end point's when none
      !> was lower)
      real(dp) :: f_profile_low = 0.0_dp
      integer :: nstarts_failed = 0          !< of its further starts, those that failed
      integer :: nstarts = 0
      integer :: nevals = 0
      type(region_stat), allocatable :: regions(:)
      real(dp), allocatable :: y(:)          !< responses with the effect, all tests
   end type effect_outcome

   !> The whole diagnosis
   type :: diagnose_result
      character(len=name_len), allocatable :: names(:)   !< of the tests
      !> How each test's data were compared (data_note; blank: every output time, every row)
      character(len=256), allocatable :: data_notes(:)
      character(len=32), allocatable :: unit(:)   !< response and unit per test
      character(len=8) :: stress_unit = ''        !< the model's stress unit
      logical, allocatable :: held(:)
      real(dp), allocatable :: noise(:)           !< noise sd per test, response unit
      !> per test, its noise sd from second differences 5 samples apart over that from
      !> neighbours (noise_correlation: 1 for independent noise)
      real(dp), allocatable :: noise_corr(:)
      real(dp), allocatable :: peak(:)
      real(dp), allocatable :: c0(:), c(:)        !< constants given and of the baseline fit
      integer, allocatable :: c_bound(:)          !< baseline constants at a search bound
      integer :: baseline_starts = 1              !< starts of the baseline fit
      integer :: baseline_iterations = 0          !< iterations of its search that was kept
      !> The baseline's objective before it was fitted again from the constants of a refit
      !> that fit the fit tests better without their effect (see baseline_left_behind), and
      !> that refit's effect (unallocated: it was not)
      real(dp) :: f0_left = 0.0_dp
      character(len=:), allocatable :: rebased_by
      !> That search ended otherwise than at its iteration or evaluation limit, or a further
      !> search from its end found nothing lower
      logical :: baseline_converged = .true.
      character(len=:), allocatable :: cnames(:)
      real(dp) :: f0 = 0.0_dp                     !< baseline objective on the fit tests
      real(dp), allocatable :: per_test0(:)       !< baseline per test (held-out: prediction)
      real(dp) :: noise_fit = 0.0_dp, noise_held = 0.0_dp  !< objective the noise explains
      !> Part of noise_held that the fitted constants' own uncertainty explains: a prediction
      !> from constants fitted to noisy tests is off by their scatter
      real(dp) :: pred_held = 0.0_dp
      real(dp) :: gap_fit = 0.0_dp, gap_held = 0.0_dp      !< structured gaps at the baseline
      !> Gaps up to these are noise: gap_z standard errors of the gap noise alone leaves
      real(dp) :: floor_fit = 0.0_dp, floor_held = 0.0_dp
      !> The held-out tests' gap and floor against their noise alone (without the constants'
      !> uncertainty): above it, the held-out data show something the noise does not
      real(dp) :: gap_held_noise = 0.0_dp, floor_held_noise = 0.0_dp
      integer :: m = 0                            !< residuals of the fit tests
      integer, allocatable :: npts(:)             !< residuals of each test (all tests)
      type(region_stat), allocatable :: regions(:)
      type(effect_outcome), allocatable :: effects(:)  !< sorted by pred_dbic
      integer :: leading = 0                      !< index into effects, 0: none confirmed
      !> Confirmed effects that explain the gap as well as the leading one (it included)
      integer, allocatable :: alike(:)
      real(dp) :: dt_sample = 0.0_dp              !< s, median sampling interval of the fit tests
      type(separation_type), allocatable :: seps(:)   !< tests that would separate alike effects
      !> Where the leader's held-out prediction is open (prediction_open), the candidate tests'
      !> discrimination between its end points that carry the least and the most of the
      !> held-out gap (a = b = leading; best 0: not computed)
      type(separation_type) :: pin
      character(len=:), allocatable :: verdict
      !> The verdict's clause of the tests that would separate what it leaves open (see
      !> separate), kept for a verdict drawn again after it
      character(len=:), allocatable :: separation
      integer :: nevals = 0
      ! For the plots: every point of every test
      integer, allocatable :: test_of(:), cls(:), cycle(:)
      logical, allocatable :: elastic(:)
      real(dp), allocatable :: t(:), y_ex(:), y_base(:)
      !> Global starts of the constants (x: log10), shared by the baseline and the refits
      real(dp), allocatable :: x_global(:, :)
      logical :: global = .false.                 !< the refits ran from the global starts
      real(dp) :: f0_global = 0.0_dp              !< the baseline's objective from them too
      real(dp), allocatable :: per_test_global(:) !< that baseline per test (fit tests)
      !> Each step's cost, in the order they ran; the marks: where the step under way began
      type(step_cost), allocatable :: steps(:)
      integer :: mark_nevals = 0
      integer(int64) :: mark_clock = 0
      real(dp) :: mark_cpu = 0.0_dp
      !> When the held-out tests show a structured gap that the fit tests do not and no
      !> effect is confirmed: the diagnosis of every test fitted together
      type(diagnose_result), allocatable :: joint
      !> The effect that explains the fit tests but does not carry to the held-out tests
      !> (form_open) and is carried to them as each is diagnosed beside the fit tests (see
      !> held_own in usharp_diagnose; 0: not run), the verdict's clause of what they have of
      !> their own, and each held-out test's per-specimen report
      integer :: own_base = 0
      character(len=:), allocatable :: own_note
      !> Each held-out test's objective with that effect and its own leading effect (the
      !> carried effect's prediction where none leads), and the own effects' parameters
      real(dp), allocatable :: own_f(:)
      integer :: own_q = 0
      character(len=report_line_len), allocatable :: own_report(:)
   end type diagnose_result

   !> Why the data leave a rate undetermined: its 95 % interval spans zero or is open, or it
   !> is closed about a rate at the end of its search box, where it does not hold
   integer, parameter, public :: rate_open = 1, rate_at_end = 2

   !> Why a diagnosis goes on to fit every test together (see joint_reason): none; the
   !> leader rests on BIC alone (see bic_only); on a fit of the held-out tests (see
   !> held_fit_only); an effect of open form fitted the fit tests better (see
   !> form_beats_leader); its prediction rests on constants at a search bound (see
   !> loose_prediction); it carries part of the held-out gap (see partial_carry); with no
   !> leader, the fit tests leave an effect's form open (see form_open); effects they show
   !> carry to no held-out test while those have a gap; or they carry nothing an effect
   !> could be fitted to while the held-out tests have a gap
   integer, parameter, public :: joint_none = 0, joint_bic_only = 1, joint_held_fit = 2, &
                                 joint_form_beats = 3, joint_loose = 4, joint_partial = 5, &
                                 joint_form_open = 6, joint_held_only = 7, joint_not_carried = 8

contains

   !> Whether the fit tests leave e's prediction of the held-out tests open: end points of its
   !> refit that they cannot tell apart carry shares of the held-out gap open_spread or more
   !> apart
   pure logical function prediction_open(e)
      type(effect_outcome), intent(in) :: e
      prediction_open = e%n_alike >= 1 .and. e%shrink_alike_hi - e%shrink_alike_lo >= open_spread
   end function prediction_open

   !> A parameter's value with its unit ('stress': the model's stress unit; '-' or '': none)
   pure function magnitude_text(name, value, unit, stress_unit) result(text)
      character(len=*), intent(in) :: name, unit, stress_unit
      real(dp), intent(in) :: value
      character(len=:), allocatable :: text
      text = trim(name)//' = '//real_str(value, 'es9.2')//unit_text(unit, stress_unit)
   end function magnitude_text

   !> A fitted parameter with its 95 % interval as the reports give it: 'name = value [lo,
   !> hi] unit', with the digits that tell the value from its interval's ends
   !> (interval_format); an end the data do not bound is open (interval_end); a parameter at
   !> a search bound (side -1, 1; 0: not) has no interval and is said to be undetermined
   pure function interval_text(name, value, lo, hi, lo_open, hi_open, side, unit, stress_unit) result(text)
      character(len=*), intent(in) :: name, unit, stress_unit
      real(dp), intent(in) :: value, lo, hi
      logical, intent(in) :: lo_open, hi_open
      integer, intent(in) :: side
      character(len=:), allocatable :: text, fmt
      fmt = interval_format(value, merge(value, lo, lo_open), merge(value, hi, hi_open))
      text = trim(name)//' = '//trim(adjustl(real_str(value, fmt)))
      if (side /= 0) then
         text = text//unit_text(unit, stress_unit)//' (at its '//side_word(side)//' search bound: not determined)'
      else
         text = text//' ['//interval_end(lo, lo_open, fmt)//', '//interval_end(hi, hi_open, fmt)//']'// &
                unit_text(unit, stress_unit)
      end if
   end function interval_text

   !> The magnitude an effect the tests could hide would have at the parameters p (one group
   !> of info's, in the catalogue's order) as a verdict says it, and whether it lies beyond
   !> the effect's physical limit: a second back stress by its saturation H3/gamma3 against
   !> the peak stress (its H3 alone, 1.3e3 ksi beside peaks of 20, says nothing), any other
   !> by its parameter j, every parameter against its plausible value (a softening's a of 60
   !> takes the drag stress below zero)
   pure subroutine hidden_size(info, p, j, peak, stress_unit, text, beyond)
      type(effect_info), intent(in) :: info
      real(dp), intent(in) :: p(:)
      !> the parameter to state (the one that grows most)
      integer, intent(in) :: j
      !> the peak stress the saturation is set against (model unit)
      real(dp), intent(in) :: peak
      character(len=*), intent(in) :: stress_unit
      character(len=64), intent(out) :: text
      logical, intent(out) :: beyond
      integer :: g
      beyond = .false.
      do g = 1, min(size(p), info%nparam)
         if (info%plausible(g) < huge(1.0_dp)) beyond = beyond .or. abs(p(g)) > info%plausible(g)
      end do
      if (info%name == 'backstress2' .and. size(p) >= 2) then
         if (p(2) > 0.0_dp) then
            text = 'H3/gamma3 = '//real_str(abs(p(1)/p(2)), 'es9.2')//unit_text('stress', stress_unit)
            beyond = beyond .or. abs(p(1)/p(2)) > peak
            return
         end if
      end if
      text = magnitude_text(info%pname(j), p(j), info%punit(j), stress_unit)
   end subroutine hidden_size

   !> 'n = 170 (upper), H2 = 1.0e+04 (lower)' for the constants at a bound (side -1: the
   !> lower, 1: the upper, 0: none, as at_bound gives them), or without their values c
   !> 'n (upper), H2 (lower)': which end a fit ran to says which way it ran away. units, if
   !> given, follow each value (' MPa', as unit_text gives them).
   pure function bound_list(names, c, side, units) result(text)
      character(len=*), intent(in) :: names(:)
      real(dp), intent(in), optional :: c(:)
      integer, intent(in) :: side(:)
      character(len=*), intent(in), optional :: units(:)
      character(len=:), allocatable :: text
      integer :: j
      text = ''
      do j = 1, min(size(names), size(side))
         if (side(j) == 0) cycle
         if (len(text) > 0) text = text//', '
         text = text//trim(names(j))
         if (present(c)) text = text//' = '//real_str(c(j), 'es10.3')
         if (present(units)) then
            if (j <= size(units)) text = text//trim(units(j))
         end if
         text = text//' ('//side_word(side(j))//')'
      end do
   end function bound_list

   !> What a verdict adds of an effect's own parameters at an end of their search box
   !> ('; H3 = 1.761E+05 MPa (upper) at its search bound, not determined by the data'; side
   !> as bound_list takes it, units the catalogue's, 'stress' as stress_unit), in both
   !> diagnoses; '' when none is
   pure function params_bound_note(names, p, side, units, stress_unit) result(text)
      character(len=*), intent(in) :: names(:), units(:), stress_unit
      real(dp), intent(in) :: p(:)
      integer, intent(in) :: side(:)
      character(len=:), allocatable :: text
      character(len=32), allocatable :: shown(:)
      integer :: n, j
      text = ''
      n = min(size(names), size(p), size(side), size(units))
      allocate (shown(n))
      do j = 1, n
         shown(j) = unit_text(units(j), stress_unit)
      end do
      if (any(side(:n) /= 0)) text = '; '//bound_list(names(:n), p(:n), side(:n), shown)// &
         ' at its search bound, not determined by the data'
   end function params_bound_note

   !> What a verdict adds of a softening fitted with a < 0, which makes the drag grow: a
   !> cyclic hardening under the softening's name (the catalogue's one form serves both
   !> signs); '' for any other effect or sign
   pure function hardening_note(name, p) result(text)
      character(len=*), intent(in) :: name
      real(dp), intent(in) :: p(:)
      character(len=:), allocatable :: text
      text = ''
      if (name /= 'softening' .or. size(p) < 1) return
      if (p(1) < 0.0_dp) text = '; with a = '//real_str(p(1), 'g0.3')// &
                                ' < 0 it is a cyclic hardening, not a softening'
   end function hardening_note

   !> 'lower' or 'upper' for the side at_bound gives (-1, 1)
   pure function side_word(side) result(word)
      integer, intent(in) :: side
      character(len=5) :: word
      word = merge('upper', 'lower', side > 0)
   end function side_word

   !> A parameter's unit as it follows its value (' K', ' MPa'): the catalogue's unit,
   !> 'stress' the model's stress unit, nothing for '-' or ''
   pure function unit_text(unit, stress_unit) result(text)
      character(len=*), intent(in) :: unit, stress_unit
      character(len=:), allocatable :: text
      text = ''
      if (unit == 'stress') then
         text = ' '//trim(stress_unit)
      else if (unit /= '-' .and. len_trim(unit) > 0) then
         text = ' '//trim(unit)
      end if
   end function unit_text

   !> Tell the listener, if any, of a step: stage, simulations so far
   subroutine tell(ctx, stage, nevals)
      type(diagnose_context), intent(in) :: ctx
      character(len=*), intent(in) :: stage
      integer, intent(in) :: nevals
      integer(int64) :: now, rate
      if (.not. associated(ctx%progress)) return
      call system_clock(now, rate)
      call ctx%progress(stage, nevals, real(now - ctx%clock0, dp)/real(max(rate, 1_int64), dp))
   end subroutine tell

   !> Close the step under way as `name` (its simulations, elapsed and processor time since
   !> the last mark) and mark the start of the next (the first call only marks)
   subroutine step_done(res, name)
      type(diagnose_result), intent(inout) :: res
      character(len=*), intent(in) :: name
      integer(int64) :: now, rate
      real(dp) :: cpu
      call system_clock(now, rate)
      call cpu_time(cpu)
      if (.not. allocated(res%steps)) then
         allocate (res%steps(0))
      else
         res%steps = [res%steps, step_cost(name, res%nevals - res%mark_nevals, &
                      real(now - res%mark_clock, dp)/real(max(rate, 1_int64), dp), cpu - res%mark_cpu)]
      end if
      res%mark_nevals = res%nevals
      res%mark_clock = now
      res%mark_cpu = cpu
   end subroutine step_done

   !> True when the fit tests had a structured gap at the baseline (above their floor)
   pure logical function fit_structured(res)
      type(diagnose_result), intent(in) :: res
      fit_structured = res%gap_fit > res%floor_fit
   end function fit_structured

   !> Each test's objective at the reference baseline (see gap_fit_ref): the global
   !> baseline's where it is the lower, against which a refit makes a test worse
   pure function per_test_ref(res) result(f)
      type(diagnose_result), intent(in) :: res
      real(dp), allocatable :: f(:)
      f = res%per_test0
      if (res%global .and. res%f0_global < res%f0 .and. allocated(res%per_test_global)) f = res%per_test_global
   end function per_test_ref

   !> The fit tests' structured gap at the reference baseline, of which the refits' shares
   !> are taken: where the global starts found a lower baseline (the reference of dAIC and
   !> dBIC), what the constants alone take from the gap there is no effect's (a second back
   !> stress reported as removing 54.9 % of a gap against the first baseline, 533.7, removed
   !> 51.4 % against the lower, 494.8)
   pure real(dp) function gap_fit_ref(res) result(gap)
      type(diagnose_result), intent(in) :: res
      gap = res%gap_fit
      if (res%global .and. res%f0_global < res%f0) gap = max(res%gap_fit - (res%f0 - res%f0_global), 0.0_dp)
   end function gap_fit_ref

   !> True when the fit tests had a structured gap and no significant refit so far takes it
   !> to their floor: the refits may have missed the effect (a score test ranks by a local
   !> step, and a fit may first have to leave the baseline's basin of the constants)
   pure logical function fit_gap_left(res)
      type(diagnose_result), intent(in) :: res
      fit_gap_left = fit_structured(res) .and. &
                     .not. any(res%effects%refitted .and. res%effects%significant .and. &
                               (1.0_dp - res%effects%shrink_fit)*gap_fit_ref(res) <= res%floor_fit)
   end function fit_gap_left

   !> The refitted effect whose constants with the effect off fit the fit tests better than
   !> the reference baseline every effect was judged against (the global stage's where it
   !> is the lower: see per_test_ref): a lower objective (what the baseline's search
   !> minimises) and a deviance lower by the significance margin of BIC (a parameter-free
   !> improvement), the lowest deviance first; 0: none. The baseline was then not the
   !> optimum of the constants, and every effect's gain against it is in part, or all, that
   !> of the better basin (thesis tests, LCF held out, a fast second back stress injected:
   !> the baseline's one start converged at 2.42, refits of a delay of 7 ms and of a machine
   !> compliance ended at 0.64 with their constants alone as low, and both were confirmed on
   !> 93 % of the held-out gap).
   pure integer function baseline_left_behind(res) result(k)
      type(diagnose_result), intent(in) :: res
      real(dp), allocatable :: ref(:)
      logical, allocatable :: fit(:)
      real(dp) :: best, dev
      integer :: i
      k = 0
      best = -bic_margin
      ref = per_test_ref(res)
      allocate (fit(size(ref)))
      fit = .true.
      if (allocated(res%held)) fit = .not. res%held
      do i = 1, size(res%effects)
         associate (e => res%effects(i))
            if (.not. e%refitted .or. .not. allocated(e%per_constants)) cycle
            dev = deviance_change(pack(res%npts, fit), pack(ref, fit), pack(e%per_constants, fit))
            if (dev < best .and. sum(e%per_constants, fit) < sum(ref, fit)) then
               best = dev
               k = i
            end if
         end associate
      end do
   end function baseline_left_behind

   !> Change of -2 ln(likelihood) when the tests' residual sums of squares go from before to
   !> after, each test's residuals of a variance of their own (profiled per test: n_i points,
   !> sum_i n_i ln(after_i/before_i)). The weighted residuals of Eq. 7 do not share one
   !> variance (a test's points carry 1/n of its weight), and one pooled variance overrates a
   !> change concentrated in a test of few points by the ratio of that test's variance to
   !> the mean (2.3 for the LCF test of a clean thesis case, which pooled gave a false alarm)
   pure real(dp) function deviance_change(n, before, after) result(d)
      !> Points per test
      integer, intent(in) :: n(:)
      !> Sums of squares per test (weighted residuals of Eq. 7), before and after
      real(dp), intent(in) :: before(:), after(:)
      d = sum(n*log_dp(max(after, tiny(1.0_dp))/max(before, tiny(1.0_dp))))
   end function deviance_change

   !> True when the candidates the screening ranked lower are to be refitted too: the fit
   !> tests have a structured gap that nothing confirmed, or nothing significant, takes to
   !> its floor; or they have none while the held-out tests have one, so that the screening,
   !> which ranks by the fit tests' residual, says little and the prediction must decide
   !> among every candidate (a temperature offset of -6.2 K with the LCF test held out: a
   !> compliance led, initial, ranked 5th, predicts the LCF test as well)
   pure logical function rest_wanted(res)
      type(diagnose_result), intent(in) :: res
      if (fit_structured(res)) then
         rest_wanted = res%leading == 0 .or. fit_gap_left(res)
      else
         rest_wanted = .not. held_quiet(res)
      end if
   end function rest_wanted

   !> True when the held-out tests had no structured gap at the baseline: there is nothing
   !> for an effect to shrink there, only a gap it must not open
   pure logical function held_quiet(res)
      type(diagnose_result), intent(in) :: res
      held_quiet = res%gap_held <= res%floor_held
   end function held_quiet

   !> True when e leaves both sets' structured gap at the noise level (at or below the
   !> floors) where one of them had a structured gap: without one, every effect leaves the
   !> noise level and only BIC tells them apart
   pure logical function leaves_noise(e, res)
      type(effect_outcome), intent(in) :: e
      type(diagnose_result), intent(in) :: res
      leaves_noise = (1.0_dp - e%shrink_fit)*gap_fit_ref(res) <= res%floor_fit .and. &
                     e%held_gap <= res%floor_held .and. (fit_structured(res) .or. .not. held_quiet(res))
   end function leaves_noise

   !> True when e removes most of the structured gap on both sets (a set without one at the
   !> baseline must stay without)
   pure logical function explains_most(e, res)
      type(effect_outcome), intent(in) :: e
      type(diagnose_result), intent(in) :: res
      explains_most = explains(e, res, .false.)
   end function explains_most

   !> True when an effect that removed a share of a set's structured gap leaves no
   !> detectable rest of it (at or below the set's floor) while the part it removed is
   !> detectable (above the floor). The share is a ratio of two noisy gaps, each scattered
   !> by a third of the floor: with a gap of twice its floor, 70 % and 100 % are alike to the
   !> data (a lag of 0.12 s with the relaxation test held out removed 73.7 % of a held-out gap
   !> of 2.3 floors, its rest at 0.6 of the floor)
   elemental logical function rest_at_noise(gap, removed, floor)
      real(dp), intent(in) :: gap      !< structured gap at the baseline
      real(dp), intent(in) :: removed  !< share of it the effect removed
      real(dp), intent(in) :: floor    !< the set's floor (3 standard errors of the gap noise)
      rest_at_noise = (1.0_dp - removed)*gap <= floor .and. removed*gap > floor
   end function rest_at_noise

   !> True when e explains the gap as far as the tests resolve it: on each set with a
   !> structured gap, most of it removed (explains_most) or its rest at the noise level with a
   !> detectable part removed (rest_at_noise). It sets the verdict's wording, "explains"
   !> against "partly explains"; what an effect must remove to be confirmed is explains_most's
   pure logical function explains_resolved(e, res)
      type(effect_outcome), intent(in) :: e
      type(diagnose_result), intent(in) :: res
      explains_resolved = explains(e, res, .true.)
   end function explains_resolved

   !> explains_most, or with resolved explains_resolved: each set's test, both must hold
   pure logical function explains(e, res, resolved)
      type(effect_outcome), intent(in) :: e
      type(diagnose_result), intent(in) :: res
      logical, intent(in) :: resolved  !< a rest below the floor counts too (rest_at_noise)
      logical :: fit_ok, held_ok
      fit_ok = e%shrink_fit >= most .or. .not. fit_structured(res)
      held_ok = e%shrink_held >= most .or. held_quiet(res) .and. e%held_gap <= res%floor_held
      if (resolved) then
         fit_ok = fit_ok .or. rest_at_noise(gap_fit_ref(res), e%shrink_fit, res%floor_fit)
         held_ok = held_ok .or. .not. held_quiet(res) .and. &
                   rest_at_noise(res%gap_held, e%shrink_held, res%floor_held)
      end if
      explains = fit_ok .and. held_ok
   end function explains

   !> Why a diagnosis should go on to fit the held-out tests too (joint_none: it should not):
   !> no effect is confirmed and the fit tests cannot say which effect there is. Either they
   !> have no structured gap, or no effect fitted to them is significant, while the held-out
   !> tests have one against their noise (with or without the constants' uncertainty on
   !> top): the fit tests carry nothing an effect could be fitted to, and the gap is the
   !> constants they leave loose (fitted together, every test reaches its noise level) or an
   !> effect only the held-out tests show (a softening of later cycles that a relaxation and
   !> a ratcheting test do not reach). Or an effect takes their structured gap to its floor
   !> (see form_open) but does not carry to the held-out tests: the fit tests show it and
   !> leave its form open (a softening and a slow hardening with other constants fit them
   !> alike), and only the held-out tests can decide the form. Or a leader's prediction
   !> cannot decide: it rests on BIC alone (see bic_only), on a fit of the held-out tests
   !> (see held_fit_only), an effect of open form fitted the fit tests better (see
   !> form_beats_leader), it rests on constants the fit tests leave at a search bound (see
   !> loose_prediction), or it carries only part of the held-out gap (see partial_carry).
   !> Or, without a leader, effects significant on the fit tests carry to none of the
   !> held-out tests while those show a gap against their noise.
   !> The first of these that holds, in this order, is the reason.
   pure integer function joint_reason(res, joint) result(why)
      type(diagnose_result), intent(in) :: res
      logical, intent(in) :: joint       !< this diagnosis is already the joint one
      why = joint_none
      if (joint) return
      if (res%leading /= 0) then
         if (bic_only(res)) then
            why = joint_bic_only
         else if (held_fit_only(res)) then
            why = joint_held_fit
         else if (form_beats_leader(res) > 0) then
            why = joint_form_beats
         else if (loose_prediction(res)) then
            why = joint_loose
         else if (partial_carry(res)) then
            why = joint_partial
         end if
      else if (fit_effects_shown(res)) then
         if (form_left_open(res)) then
            why = joint_form_open
         else if (res%gap_held_noise > res%floor_held_noise) then
            ! Effects lower the fit tests' BIC, none to their floor, and none carries to the
            ! held-out tests, which have a gap of their own: on real tests the usual case (the
            ! Alloy 617 tests with E12 and J2 held out: nine effects significant, none
            ! confirmed), which had ended without fitting every test and without saying why
            why = joint_not_carried
         end if
      else if (res%gap_held_noise > res%floor_held_noise) then
         ! The fit tests' gap below its floor, yet an effect may lower their BIC (the floor
         ! tests every direction at once, BIC the effect's own): a softening of 0.11 with the
         ! relaxation test held out, fitted to the other two as a hardening (BIC -587) that
         ! made the relaxation test worse, had left the verdict at "no significant effect"
         why = joint_held_only
      else if (form_left_open(res)) then
         why = joint_form_open
      end if
   end function joint_reason

   !> True when a diagnosis should go on to fit the held-out tests too (see joint_reason)
   pure logical function joint_wanted(res, joint)
      type(diagnose_result), intent(in) :: res
      logical, intent(in) :: joint       !< this diagnosis is already the joint one
      joint_wanted = joint_reason(res, joint) /= joint_none
   end function joint_wanted

   !> The leader rests on its prediction of the held-out tests alone (the fit tests have no
   !> structured gap) while the baseline ran away: its constants at a search bound, where the
   !> covariance that puts their uncertainty into the held-out floor does not hold, so any
   !> effect that moves them meets the held-out tests (with the LCF test held out, compliance,
   !> initial, temperature and drift each removed 100 % of a predicted gap of 1418 against a
   !> noise part of 0.43, the data made with a second back stress of 2.23 ksi)
   pure logical function loose_prediction(res)
      type(diagnose_result), intent(in) :: res
      loose_prediction = .false.
      if (res%leading == 0 .or. .not. allocated(res%c_bound)) return
      if (.not. any(res%c_bound /= 0)) return
      loose_prediction = .not. fit_structured(res) .and. .not. held_quiet(res) .and. &
                         .not. res%effects(res%leading)%held_fitted
   end function loose_prediction

   !> The leader's prediction carries less than most of the held-out tests' structured gap
   !> and leaves a rest above their floor, while on the fit tests it leaves none above theirs.
   !> Fitted to the fit tests alone its parameters may be what fails (a softening of 0.17, fitted to the LCF and ratcheting tests as a slower one, carried 55 % of the
   !> relaxation test's gap), or another effect adds to it: only every test fitted together
   !> tells which, and how much of every gap the effect closes. So too where the fit tests
   !> leave its prediction open (see prediction_open) and it leaves a rest above the floor:
   !> the held-out tests hold what fixes the parameters it depends on. So too for an effect
   !> per test, whose held-out values are fitted with the fit tests' constants carried over:
   !> those constants can be what fails (a drift with the LCF test held out, fitted to the
   !> relaxation and ratcheting tests, met the LCF test's gap by 72.3 %, its constants alone
   !> 68.3 %). Not where the baseline ran to a bound (see loose_prediction), whose joint
   !> stage decides alone.
   pure logical function partial_carry(res)
      type(diagnose_result), intent(in) :: res
      partial_carry = .false.
      if (res%leading == 0 .or. .not. allocated(res%held)) return
      if (.not. any(res%held) .or. held_quiet(res) .or. loose_prediction(res)) return
      associate (e => res%effects(res%leading))
         if ((1.0_dp - e%shrink_fit)*gap_fit_ref(res) > res%floor_fit) return
         partial_carry = (e%shrink_held < most .or. prediction_open(e)) .and. held_rest_open(res)
      end associate
   end function partial_carry

   !> The leader's prediction leaves the held-out tests a structured gap above their floor
   pure logical function held_rest_open(res)
      type(diagnose_result), intent(in) :: res
      held_rest_open = .false.
      if (res%leading == 0) return
      held_rest_open = (1.0_dp - res%effects(res%leading)%shrink_held)*res%gap_held > res%floor_held
   end function held_rest_open

   !> An effect that explains the fit tests better than the leader by BIC (by more than
   !> bic_margin) and leaves their form open (see form_open), while the leader explains
   !> little of them (their gap below its floor, or less than most of it removed) or its
   !> prediction leaves the held-out tests a rest above their floor; 0 when there is none.
   !> The fit tests then favour that effect's form, and only every test fitted together can
   !> say whether its parameters or its form failed on the held-out tests: with the
   !> relaxation test held out, a second back stress led (67 % of the fit tests' gap) for a
   !> softening of 0.17 whose fit to the other two tests, a hardening, was better by BIC 406;
   !> with the LCF test held out, a fast second back stress (gamma3 4179) fitted to the
   !> other two at constants run to a bound (BIC -2332) made the LCF test worse, and a
   !> hardening (BIC -2322) was named for 86 % of its gap, the rest 39 times its floor
   pure integer function form_beats_leader(res) result(k)
      type(diagnose_result), intent(in) :: res
      integer :: j
      k = 0
      if (res%leading == 0) return
      associate (e => res%effects(res%leading))
         if (fit_structured(res) .and. e%shrink_fit >= most .and. .not. held_rest_open(res)) return
         do j = 1, size(res%effects)
            if (.not. form_open(res%effects(j), res)) cycle
            if (res%effects(j)%dbic >= e%dbic - bic_margin) cycle
            if (k == 0) then
               k = j
            else if (res%effects(j)%dbic < res%effects(k)%dbic) then
               k = j
            end if
         end do
      end associate
   end function form_beats_leader

   !> True when the fit tests show an effect (see fit_effects_shown) or leave an effect's form
   !> open (see form_left_open): why a prediction from them could not confirm one, as the
   !> verdict and the report word it
   pure logical function fit_effect_not_carried(res)
      type(diagnose_result), intent(in) :: res
      fit_effect_not_carried = fit_effects_shown(res) .or. form_left_open(res)
   end function fit_effect_not_carried

   !> True when some effect leaves the fit tests' form open (see form_open)
   pure logical function form_left_open(res)
      type(diagnose_result), intent(in) :: res
      integer :: j
      form_left_open = any([(form_open(res%effects(j), res), j=1, size(res%effects))])
   end function form_left_open

   !> True when an effect leads by its own BIC on the fit tests alone: the held-out tests had
   !> no structured gap above their floor (nothing for a prediction to confirm), and the fit
   !> tests had none either or the effect leaves most of theirs. A held-out floor (the noise
   !> and the constants' uncertainty) can be too wide to tell the leader from the effects it
   !> beat: relaxation and ratcheting tests leave the constants so loose that an LCF test's
   !> floor is a chi-square of thousands, and a compliance led by BIC -28 to -78 for a second
   !> back stress or a temperature offset that only the LCF test shows.
   pure logical function bic_only(res)
      type(diagnose_result), intent(in) :: res
      bic_only = .false.
      if (res%leading == 0 .or. .not. allocated(res%held)) return
      if (.not. any(res%held) .or. .not. held_quiet(res)) return
      bic_only = .not. fit_structured(res)
      if (fit_structured(res)) bic_only = res%effects(res%leading)%shrink_fit < most
   end function bic_only

   !> True when the leading effect was confirmed on the held-out tests by its parameters
   !> fitted to them (an effect per test), while on the fit tests it explains little: they
   !> have no structured gap, or it leaves most of theirs. Its evidence is then a fit of the
   !> held-out tests, and only every effect fitted to them too compares fairly: a drift led
   !> for a saturating softening of 0.13 with the relaxation test held out (12.6 % of the
   !> fit tests' gap, 83.9 % of the held-out gap by the relaxation test's own drift), where
   !> the softening fitted to the fit tests alone had taken the wrong sign (-0.22)
   pure logical function held_fit_only(res)
      type(diagnose_result), intent(in) :: res
      held_fit_only = .false.
      if (res%leading == 0 .or. .not. allocated(res%held)) return
      associate (e => res%effects(res%leading))
         if (.not. e%held_fitted .or. held_quiet(res)) return
         held_fit_only = .not. fit_structured(res)
         if (fit_structured(res)) held_fit_only = e%shrink_fit < most
      end associate
   end function held_fit_only

   !> True when the fit tests have a structured gap and an effect fitted to them is significant
   pure logical function fit_effects_shown(res)
      type(diagnose_result), intent(in) :: res
      fit_effects_shown = fit_structured(res) .and. any(res%effects%significant)
   end function fit_effects_shown

   !> True when e, significant, of a plausible and resolved magnitude, takes the fit tests'
   !> structured gap to its floor without being confirmed on the held-out tests
   pure logical function form_open(e, res)
      type(effect_outcome), intent(in) :: e
      type(diagnose_result), intent(in) :: res
      form_open = e%refitted .and. e%significant .and. e%plausible .and. e%resolved .and. &
                  .not. e%confirmed .and. (1.0_dp - e%shrink_fit)*gap_fit_ref(res) <= res%floor_fit
   end function form_open

   !> The catalogue number of the effect a diagnosis names first (0: none): its joint stage's
   !> where that decides (see joint_decides), else the leading confirmed effect
   pure integer function named_effect(res) result(k)
      type(diagnose_result), intent(in) :: res
      k = 0
      if (joint_decides(res)) then
         if (res%joint%leading > 0) k = res%joint%effects(res%joint%leading)%k
      else if (res%leading > 0) then
         k = res%effects(res%leading)%k
      end if
   end function named_effect

   !> True when a diagnosis's joint stage (every test fitted) decides its verdict: it confirms
   !> an effect, or every test fitted together is at the noise level. Otherwise the joint
   !> stage is reported beside the diagnosis of the fit tests, which names the effect.
   pure logical function joint_decides(res)
      type(diagnose_result), intent(in) :: res
      joint_decides = .false.
      if (.not. allocated(res%joint)) return
      ! A leader the prediction confirmed, which the joint stage only adds to, stays named
      if (joint_reason(res, .false.) == joint_partial) return
      joint_decides = res%joint%leading > 0 .or. .not. fit_structured(res%joint)
   end function joint_decides
end module usharp_diagnose_types
