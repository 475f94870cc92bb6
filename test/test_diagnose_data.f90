!> Tests of the diagnosis on measured-like data: regions from the kinematics of a noisy,
!> quantised control, elastic and inelastic points from the model's inelastic rate, the
!> serrated-flow signature, and the extensometer drift
module test_diagnose_data
   use testdrive, only: error_type, unittest_type, new_unittest, check, test_failed
   use usharp_kinds, only: dp
   use usharp_error, only: uerror => error_type
   use usharp_history, only: history_type, cyclic_history, output_times, control_strain, ratchet_history
   use usharp_model_miller, only: miller_model, model_setup
   use usharp_simulation, only: sim_result, solver_options
   use usharp_cvode_driver, only: simulate_cvode
   use usharp_regions, only: point_classes, inelastic_points, serration_of, serration_stat, noise_sd, &
                             kinematics_of, control_kinematics, class_loading, class_unloading, &
                             class_reversal, class_hold
   use usharp_strings, only: str, real_str, report_line_len
   use usharp_rng, only: rng_type
   use usharp_optimiser, only: least_squares_type, optimum_type, reason_itermax
   use usharp_levenberg, only: levenberg_marquardt
   use usharp_diagnose_profile, only: profile_interval, profile_result, f1_95, chi2_95
   use usharp_config, only: run_config
   use usharp_input, only: read_config
   use usharp_objective, only: fit_problem, setup_problem
   use usharp_experiment, only: experiment_type
   use usharp_effects, only: test_effects, effect_index, n_effects
   use usharp_effect_problem, only: effect_problem, new_effect_problem, failed_objective
   use usharp_diagnose_options, only: diagnose_options, diagnose_options_of
   use usharp_diagnose_specimen, only: specimen_result, specimen_run, specimen_report, own_measure, specimen_verdict
   use usharp_diagnose, only: diagnose_result, diagnose_run, diagnose_baseline, diagnose_context, &
                              named_effect, joint_decides
   use usharp_diagnose_verdict, only: conclude, verdict_of
   use usharp_diagnose_types, only: baseline_left_behind, prediction_open, separating_d
   use usharp_diagnose_numerics, only: bic_power, power_lambda, lm_ftol, lm_updates
   use usharp_diagnose_baseline, only: converge_baseline
   use usharp_identify, only: chi2_quantile_95
   use test_util, only: write_text, read_text
   implicit none
   private
   public :: collect_diagnose_data

   !> y = a exp(-b t) + noise at fixed t: x = (a, b)
   type, extends(least_squares_type) :: decay_problem
      real(dp), allocatable :: t(:), y(:)
      !> The model fails to simulate for b above this
      real(dp) :: fail_above = huge(1.0_dp)
   contains
      procedure :: residuals => decay_residuals
      procedure :: nres => decay_nres
      procedure :: eval => decay_eval
   end type decay_problem

contains

   subroutine collect_diagnose_data(testsuite)
      type(unittest_type), allocatable, intent(out) :: testsuite(:)
      testsuite = [ &
         new_unittest('classes-of-a-quantised-noisy-strain', test_quantised), &
         new_unittest('relaxation-logged-coarsely-no-effect', test_coarse_log), &
         new_unittest('holds-only-where-the-strain-is-steady', test_measured_hold), &
         new_unittest('ratchet-steps-are-not-all-reversal', test_ratchet_classes), &
         new_unittest('inelastic-from-the-model-rate', test_inelastic), &
         new_unittest('serration-signature-in-the-residual', test_serration), &
         new_unittest('profile-interval-coverage-monte-carlo', test_profile_coverage), &
         new_unittest('profile-left-open-where-the-model-fails', test_profile_failures), &
         new_unittest('profile-starts-again-from-a-lower-point', test_profile_recentre), &
         new_unittest('leader-refitted-from-a-lower-point-of-its-profile', test_leader_lower), &
         new_unittest('per-specimen-names-a-drifting-extensometer', test_specimen_drift), &
         new_unittest('power-against-monte-carlo', test_power_monte_carlo), &
         new_unittest('clean-specimen-against-loose-replicates', test_specimen_clean), &
         new_unittest('specimen-temperature-at-low-end-named', test_specimen_temperature_low), &
         new_unittest('specimen-gain-at-low-end-named', test_specimen_gain_low), &
         new_unittest('held-out-test-beside-the-fit-tests-with-a-carried-softening', test_specimen_carried), &
         new_unittest('clean-specimen-noisier-than-its-replicates', test_specimen_noisier), &
         new_unittest('independent-data-clean-modulus-temperature', test_independent), &
         new_unittest('lcf-held-out-softening-found-with-every-test-fitted', test_joint), &
         new_unittest('softening-refitted-in-the-basin-of-its-sign', test_softening_sign), &
         new_unittest('held-out-prediction-of-loose-constants-confirms-nothing', test_loose_constants), &
         new_unittest('drift-in-one-fit-test-stated-as-missable', test_drift_one_test), &
         new_unittest('fast-second-back-stress-found-at-its-rate', test_fast_backstress), &
         new_unittest('baseline-left-behind-is-fitted-again', test_baseline_left_behind), &
         new_unittest('baseline-searched-past-its-iteration-limit', test_baseline_continued), &
         new_unittest('clean-data-joint-stage-against-the-optimum', test_joint_rebaseline), &
         new_unittest('joint-stage-starts-from-the-fit-tests-refit', test_joint_carried), &
         new_unittest('open-prediction-weighted-by-the-fit-tests', test_open_weighted), &
         new_unittest('lag-screened-at-a-realistic-step', test_lag_screening), &
         new_unittest('serrated-flow-named-in-the-verdict', test_serrated_verdict), &
         new_unittest('held-out-floor-holds-the-constants-uncertainty', test_prediction_spread), &
         new_unittest('noise-from-the-residual-not-the-curvature', test_residual_noise)]
   end subroutine collect_diagnose_data

   !> A measured strain: the command sampled every dt s with Gaussian noise of sd (strain)
   !> and rounded to quantum q, as a dense history of its own
   subroutine measured(cmd, dt, sd, q, seed, hist)
      type(history_type), intent(in) :: cmd
      real(dp), intent(in) :: dt, sd, q
      integer, intent(in) :: seed
      type(history_type), intent(out) :: hist
      type(rng_type) :: rng
      integer :: i
      call rng%seed(seed)
      hist%control = control_strain
      hist%t = output_times(cmd, dt)
      allocate (hist%v(size(hist%t)))
      do i = 1, size(hist%t)
         hist%v(i) = q*nint((cmd%value_at(hist%t(i)) + sd*rng%normal())/q)
      end do
   end subroutine measured

   !> Two fully reversed cycles of +-0.15 % at 1e-3/s sampled at 0.03 s, quantised at 1e-5
   !> with noise of 1e-5 (Alloy 617 B-1): exactly four turns, two cycles, no hold (the old
   !> slope test called every flat pair of samples a hold), and each branch's class from
   !> its direction
   subroutine test_quantised(error)
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: e
      type(history_type) :: cmd, hist
      type(control_kinematics) :: kin
      integer, allocatable :: cls(:), cyc(:)
      real(dp), allocatable :: t(:)
      integer :: i, nbad
      real(dp) :: v, tq
      call cyclic_history(0.003_dp, 0.0_dp, 1.0e-3_dp, 0.0_dp, 2, 0.0_dp, 0.0_dp, cmd, e)
      call check(error, .not. allocated(e), 'history failed')
      if (allocated(error)) return
      call measured(cmd, 0.03_dp, 1.0e-5_dp, 1.0e-5_dp, 7, hist)
      kin = kinematics_of(hist)
      call check(error, size(kin%tturn) == 4, 'turns: '//str(size(kin%tturn))//', expected 4')
      if (allocated(error)) return
      call check(error, count(kin%hold) == 0, str(count(kin%hold))//' hold segments in a test without holds')
      if (allocated(error)) return
      t = hist%t
      allocate (cls(size(t)), cyc(size(t)))
      call point_classes(hist, t, cls, cyc)
      call check(error, maxval(cyc) == 2 .and. minval(cyc) == 1, 'cycles '//str(minval(cyc))//' to '//str(maxval(cyc)))
      if (allocated(error)) return
      ! Away from the turns (quarter period 1.5 s) the class follows the command
      tq = 1.5_dp
      nbad = 0
      do i = 1, size(t)
         v = cmd%value_at(t(i))
         if (abs(abs(v) - 0.0015_dp) < 0.0004_dp .or. abs(v) < 0.0001_dp) cycle
         if (modulo(t(i), 4*tq) < tq .or. modulo(t(i), 4*tq) > 2*tq .and. modulo(t(i), 4*tq) < 3*tq) then
            if (cls(i) /= class_loading) nbad = nbad + 1
         else
            if (cls(i) /= class_unloading) nbad = nbad + 1
         end if
      end do
      call check(error, nbad == 0, str(nbad)//' points of a branch in the wrong class')
   end subroutine test_quantised

   !> A 1 % cycle with a 60 s hold at the peak, sampled at 0.2 s, quantised and noisy: the
   !> hold and only the hold is one, the points after it are the reversal
   subroutine test_measured_hold(error)
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: e
      type(history_type) :: cmd, hist
      integer, allocatable :: cls(:), cyc(:)
      real(dp), allocatable :: t(:)
      integer :: i, nbad
      call cyclic_history(0.01_dp, 0.0_dp, 1.0e-3_dp, 0.0_dp, 1, 60.0_dp, 0.0_dp, cmd, e)
      call check(error, .not. allocated(e), 'history failed')
      if (allocated(error)) return
      call measured(cmd, 0.2_dp, 1.0e-5_dp, 1.0e-5_dp, 11, hist)
      t = hist%t
      allocate (cls(size(t)), cyc(size(t)))
      call point_classes(hist, t, cls, cyc)
      nbad = 0
      do i = 1, size(t)
         ! the command holds from 5 s to 65 s; allow one sample either side
         if (t(i) > 5.5_dp .and. t(i) < 64.5_dp) then
            if (cls(i) /= class_hold) nbad = nbad + 1
         else if (t(i) < 4.5_dp .or. t(i) > 65.5_dp) then
            if (cls(i) == class_hold) nbad = nbad + 1
         end if
      end do
      call check(error, nbad == 0, str(nbad)//' points misclassed as to the hold')
      if (allocated(error)) return
      do i = 1, size(t)
         if (t(i) > 65.3_dp .and. t(i) < 65.8_dp .and. cls(i) /= class_reversal) nbad = nbad + 1
      end do
      call check(error, nbad == 0, str(nbad)//' points after the hold not in the reversal')
   end subroutine test_measured_hold

   !> The thesis ratcheting test (steps of +0.05 % and -0.025 % in a 0.4 % range): 30 turns,
   !> and the reversal is the first 30 % of each step, not the whole test (10 % of the range
   !> is more than a step)
   subroutine test_ratchet_classes(error)
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: e
      type(history_type) :: hist
      integer, allocatable :: cls(:), cyc(:)
      real(dp), allocatable :: t(:)
      real(dp) :: share
      call ratchet_history(0.0005_dp, 0.00025_dp, 15, 40.0_dp, hist, e)
      call check(error, .not. allocated(e), 'history failed')
      if (allocated(error)) return
      t = output_times(hist, 1.0_dp)
      allocate (cls(size(t)), cyc(size(t)))
      call point_classes(hist, t, cls, cyc)
      share = real(count(cls == class_reversal), dp)/size(t)
      call check(error, share > 0.2_dp .and. share < 0.4_dp .and. maxval(cyc) == 15, &
                 'reversal share '//real_str(share, 'f0.3')//', cycles '//str(maxval(cyc)))
   end subroutine test_ratchet_classes

   !> A 1 % cycle with a hold, thesis model (yields near 0.09 % strain): the first loading is
   !> elastic at 0.03 % and inelastic near the peak, the hold (relaxation) is inelastic, and
   !> the first 0.03 % of the unloading from the hold is elastic
   subroutine test_inelastic(error)
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: e
      type(history_type) :: cmd
      type(miller_model) :: model
      type(solver_options) :: opts
      type(sim_result) :: res
      logical, allocatable :: inel(:)
      real(dp), allocatable :: t(:)
      call model_setup(model, e)
      call cyclic_history(0.01_dp, 0.0_dp, 1.0e-3_dp, 0.0_dp, 1, 60.0_dp, 0.0_dp, cmd, e)
      t = output_times(cmd, 0.1_dp)
      call simulate_cvode(model, cmd, t, opts, res, e)
      call check(error, .not. allocated(e), 'simulation failed')
      if (allocated(error)) return
      inel = inelastic_points(res%strain, res%eps_in)
      call check(error, .not. inel(at(0.3_dp)), 'start of loading inelastic')
      if (allocated(error)) return
      call check(error, inel(at(4.5_dp)), 'loading near the peak elastic')
      if (allocated(error)) return
      call check(error, inel(at(30.0_dp)), 'relaxation elastic')
      if (allocated(error)) return
      call check(error, .not. inel(at(65.3_dp)), 'unloading from the hold inelastic: '// &
                 real_str(res%stress(at(65.3_dp)), 'es10.3'))
   contains
      integer function at(time)
         real(dp), intent(in) :: time
         at = minloc(abs(t - time), 1)
      end function at
   end subroutine test_inelastic

   !> A residual of a smooth structured gap plus white noise has no serration signature
   !> (in 20 draws, p > 1e-3 in all but at most one); with an oscillation of 0.7 noise sd
   !> and a period of 9 samples added, p < 1e-6 and the period and amplitude come back
   subroutine test_serration(error)
      type(error_type), allocatable, intent(out) :: error
      type(rng_type) :: rng
      type(serration_stat) :: st
      real(dp), allocatable :: e(:)
      logical, allocatable :: mask(:)
      integer :: i, rep, nfalse, n
      real(dp), parameter :: pi = acos(-1.0_dp)
      n = 600
      call rng%seed(5)
      allocate (e(n), mask(n))
      mask = .true.
      nfalse = 0
      do rep = 1, 20
         do i = 1, n
            e(i) = 3.0_dp*sin(2.0_dp*pi*i/n) + 2.0_dp*(real(i, dp)/n)**2 + rng%normal()
         end do
         st = serration_of(e, mask)
         if (st%p < 1.0e-3_dp) nfalse = nfalse + 1
      end do
      call check(error, nfalse <= 1, str(nfalse)//' of 20 noise residuals flagged as serrated')
      if (allocated(error)) return
      do i = 1, n
         e(i) = e(i) + 0.7_dp*sin(2.0_dp*pi*i/9.0_dp)
      end do
      st = serration_of(e, mask)
      call check(error, st%p < 1.0e-6_dp .and. abs(st%period - 9.0_dp) < 0.3_dp .and. &
                 abs(st%amplitude - 0.7_dp) < 0.2_dp, 'oscillation: p '//real_str(st%p, 'es10.2')// &
                 ', period '//real_str(st%period, 'f0.2')//', amplitude '//real_str(st%amplitude, 'f0.3'))
   end subroutine test_serration

   !> Coverage of the profile-likelihood interval in 200 Monte Carlo repetitions of a decay
   !> y = exp(-0.8 t) on 12 points over 0-4 s with noise sd 0.15 (b profiled in its log, the
   !> objective's rise at the ends F(1, m - 2) s**2, s**2 = f/(m - 2)): 95 % +- 3.5 %. The
   !> Wald interval of the same fits is printed for comparison (a small sample: its skew
   !> shows)
   subroutine test_profile_coverage(error)
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: e
      type(decay_problem) :: dp_
      type(optimum_type) :: opt
      type(profile_result) :: pr
      type(rng_type) :: rng
      real(dp), parameter :: b_true = 0.8_dp, sd = 0.15_dp
      real(dp) :: s2, cov(2, 2), jac(12, 2), det, se
      integer :: rep, i, hits, wald, nrep, m
      nrep = 200
      m = 12
      call rng%seed(17)
      dp_%t = [(4.0_dp*(i - 1)/(m - 1), i=1, m)]
      allocate (dp_%y(m))
      hits = 0
      wald = 0
      do rep = 1, nrep
         do i = 1, m
            dp_%y(i) = exp(-b_true*dp_%t(i)) + sd*rng%normal()
         end do
         call levenberg_marquardt(dp_, [1.0_dp, 1.0_dp], [-10.0_dp, 1.0e-6_dp], [10.0_dp, 100.0_dp], &
                                  1.0e-7_dp, 1.0e-12_dp, 200, 5000, opt, e)
         call check(error, .not. allocated(e), 'fit failed')
         if (allocated(error)) return
         s2 = opt%f/(m - 2)
         jac(:, 1) = -exp(-opt%x(2)*dp_%t)
         jac(:, 2) = opt%x(1)*dp_%t*exp(-opt%x(2)*dp_%t)
         cov = matmul(transpose(jac), jac)
         det = cov(1, 1)*cov(2, 2) - cov(1, 2)**2
         se = sqrt(s2*cov(1, 1)/det)
         if (abs(opt%x(2) - b_true) < 1.959964_dp*se) wald = wald + 1
         call profile_interval(dp_, opt%x, opt%f, 2, [-10.0_dp, 1.0e-6_dp], [10.0_dp, 100.0_dp], &
                               1.0e-7_dp, se, s2*f1_95(m - 2)/chi2_95, .true., 2000, pr, e)
         call check(error, .not. allocated(e), 'profile failed')
         if (allocated(error)) return
         if (pr%lo <= b_true .and. b_true <= pr%hi) hits = hits + 1
      end do
      write (*, '(4x,a)') 'profile coverage '//str(hits)//'/'//str(nrep)//', Wald '//str(wald)//'/'//str(nrep)
      call check(error, abs(real(hits, dp)/nrep - 0.95_dp) <= 0.035_dp, 'profile coverage '// &
                 str(hits)//' of '//str(nrep))
   end subroutine test_profile_coverage

   !> A profile walk into values at which the model fails to simulate: the end is left open at
   !> the last value that simulated, not closed at the optimum as if the objective had risen
   !> without bound (the failures' penalty, 2e10); the other end closes as before
   subroutine test_profile_failures(error)
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: e
      type(decay_problem) :: dp_
      type(optimum_type) :: opt
      type(profile_result) :: pr, pr0
      call decay_case(dp_, opt, error)
      if (allocated(error)) return
      call decay_profile(dp_, opt%x, opt%f, opt, pr0, e)
      call check(error, .not. allocated(e) .and. .not. pr0%hi_open, 'the profile without failures')
      if (allocated(error)) return
      ! The model fails above half-way to the interval's upper end
      dp_%fail_above = opt%x(2) + 0.5_dp*(pr0%hi - opt%x(2))
      call decay_profile(dp_, opt%x, opt%f, opt, pr, e)
      call check(error, .not. allocated(e), 'profile failed')
      if (allocated(error)) return
      call check(error, pr%hi_open .and. pr%hi > opt%x(2) + 0.1_dp*(pr0%hi - opt%x(2)) .and. &
                 pr%hi <= dp_%fail_above, 'upper end '//real_str(pr%hi, 'es12.5')//' open '// &
                 merge('T', 'F', pr%hi_open)//' for a model failing above '//real_str(dp_%fail_above, 'es12.5')// &
                 ' (optimum '//real_str(opt%x(2), 'es12.5')//')')
      if (allocated(error)) return
      call check(error, .not. pr%lo_open .and. abs(pr%lo - pr0%lo) <= 1.0e-9_dp*abs(pr0%lo), &
                 'the lower end as before')
   end subroutine test_profile_failures

   !> A profile asked from a point that is not the optimum (b at 70 % of the way to the upper
   !> end of its interval, a refitted there: the objective 0.49 of the threshold above the
   !> minimum): its walk meets lower points and starts again from them, so its ends are those
   !> of the profile from the optimum, within 5 % of the interval's half width (from the
   !> given point, without starting again, the lower end moves by about a fifth of it)
   subroutine test_profile_recentre(error)
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: e
      type(decay_problem) :: dp_
      type(optimum_type) :: opt
      type(profile_result) :: pr, pr0
      real(dp) :: xc(2), fc, ex(12), half
      call decay_case(dp_, opt, error)
      if (allocated(error)) return
      call decay_profile(dp_, opt%x, opt%f, opt, pr0, e)
      call check(error, .not. allocated(e) .and. .not. (pr0%lo_open .or. pr0%hi_open), &
                 'the profile from the optimum')
      if (allocated(error)) return
      ! b part of the way up, a at its least squares value for that b (linear in a)
      xc(2) = opt%x(2) + 0.7_dp*(pr0%hi - opt%x(2))
      ex = exp(-xc(2)*dp_%t)
      xc(1) = sum(dp_%y*ex)/sum(ex**2)
      fc = sum((dp_%y - xc(1)*ex)**2)
      call check(error, fc - opt%f > 0.3_dp*pr0%threshold, 'the given point '// &
                 real_str((fc - opt%f)/pr0%threshold, 'f0.3')//' of the threshold above the optimum')
      if (allocated(error)) return
      call decay_profile(dp_, xc, fc, opt, pr, e)
      call check(error, .not. allocated(e), 'profile failed')
      if (allocated(error)) return
      half = 0.5_dp*(pr0%hi - pr0%lo)
      call check(error, .not. (pr%lo_open .or. pr%hi_open) .and. abs(pr%lo - pr0%lo) <= 0.05_dp*half .and. &
                 abs(pr%hi - pr0%hi) <= 0.05_dp*half .and. pr%f_centre <= opt%f + 0.05_dp*pr0%threshold, &
                 'from the point off the optimum ['//real_str(pr%lo, 'es12.5')//', '//real_str(pr%hi, 'es12.5')// &
                 '], from the optimum ['//real_str(pr0%lo, 'es12.5')//', '//real_str(pr0%hi, 'es12.5')//']')
   end subroutine test_profile_recentre

   !> The decay data of seed 5 (y = exp(-0.8 t), noise sd 0.15, 12 points over 0-4 s) and
   !> their least squares fit opt
   subroutine decay_case(dp_, opt, error)
      type(decay_problem), intent(out) :: dp_
      type(optimum_type), intent(out) :: opt
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: e
      type(rng_type) :: rng
      integer :: i
      call rng%seed(5)
      dp_%t = [(4.0_dp*(i - 1)/11.0_dp, i=1, 12)]
      dp_%y = [(exp(-0.8_dp*dp_%t(i)) + 0.15_dp*rng%normal(), i=1, 12)]
      call levenberg_marquardt(dp_, [1.0_dp, 1.0_dp], [-10.0_dp, 1.0e-6_dp], [10.0_dp, 100.0_dp], &
                               1.0e-7_dp, 1.0e-12_dp, 200, 5000, opt, e)
      call check(error, .not. allocated(e), 'fit failed')
   end subroutine decay_case

   !> The profile of b (in its log) from the point x (objective f) of the decay case, its
   !> first step and variance scale from the fit opt (0.3 b, f/10)
   subroutine decay_profile(dp_, x, f, opt, pr, e)
      type(decay_problem), intent(in) :: dp_
      real(dp), intent(in) :: x(:), f
      type(optimum_type), intent(in) :: opt
      type(profile_result), intent(out) :: pr
      type(uerror), allocatable, intent(out) :: e
      call profile_interval(dp_, x, f, 2, [-10.0_dp, 1.0e-6_dp], [10.0_dp, 100.0_dp], 1.0e-7_dp, &
                            0.3_dp*opt%x(2), opt%f/10.0_dp, .true., 2000, pr, e)
   end subroutine decay_profile

   !> Three cyclic tests of the thesis model, the third with an extensometer drift of 8e-6/s
   !> (0.04 % over its 48 s) and 0.5 % noise: fitted alone against the constants of the two
   !> others, drift ranks first and its profile interval holds the truth
   subroutine test_specimen_drift(error)
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: e
      type(run_config) :: cfg
      type(diagnose_options) :: opts
      type(test_effects) :: base
      type(experiment_type), allocatable :: exps(:)
      type(specimen_result) :: sr
      real(dp), parameter :: d_true = 8.0e-6_dp
      integer :: i, j
      logical :: ok
      call drift_case("'scatter', 'lag', 'drift'", d_true, 23, cfg, opts, exps, error)
      if (allocated(error)) return
      call specimen_run(cfg, 3, opts, .true., sr, e, exps)
      call check(error, .not. allocated(e), 'per-specimen diagnosis failed')
      if (allocated(error)) return
      if (.not. (sr%effects(1)%name == 'drift' .and. sr%effects(1)%significant)) then
         block
            character(len=report_line_len), allocatable :: lines(:)
            lines = specimen_report(sr)
            write (*, '(a)') (trim(lines(i)), i=1, size(lines))
         end block
      end if
      call check(error, sr%effects(1)%name == 'drift' .and. sr%effects(1)%significant, &
                 'ranked first: '//trim(sr%effects(1)%name))
      if (allocated(error)) return
      call check(error, sr%effects(1)%p_lo(1) <= d_true .and. d_true <= sr%effects(1)%p_hi(1), &
                 'drift '//real_str(sr%effects(1)%p(1), 'es10.3')//' ['//real_str(sr%effects(1)%p_lo(1), &
                 'es10.3')//', '//real_str(sr%effects(1)%p_hi(1), 'es10.3')//'] misses 8e-6')
      if (allocated(error)) return
      ! The verdict gives the drift's size with its interval
      block
         character(len=report_line_len), allocatable :: lines(:)
         character(len=:), allocatable :: verdict
         lines = specimen_report(sr)
         verdict = ''
         do j = 1, size(lines)
            if (index(lines(j), '**Verdict:**') == 1) verdict = trim(lines(j))
         end do
         call check(error, index(verdict, 'explains how') > 0 .and. index(verdict, '; fitted d = ') > 0 .and. &
                    index(verdict, ' 1/s') > 0, verdict)
      end block
      if (allocated(error)) return
      ! The power statement: the drift's chi-square at the low end of its range (2e-5 strain
      ! over the test), scaled to the injected drift (the signal is linear in it), is the fall
      ! of the specimen's chi-square that fitting the drift gives (expected: lambda + 1, within
      ! 3 sd of a noncentral chi-square), and the signal simulated at the injected drift
      block
         type(fit_problem) :: prob3
         type(effect_problem) :: e3
         real(dp), allocatable :: r1(:), r0(:)
         real(dp) :: duration, scaled, observed, direct
         duration = maxval(exps(3)%t) - minval(exps(3)%t)
         scaled = sr%effects(1)%lambda_low*(d_true*duration/2.0e-5_dp)**2
         observed = (sr%f0 - sr%effects(1)%f_after)/(sr%f0/sr%m)
         call check(error, abs(observed - scaled - 1.0_dp) < 3.0_dp*sqrt(2.0_dp*(1.0_dp + 2.0_dp*scaled)), &
                    'drift chi-square at the injected drift: '//real_str(scaled, 'es10.3')// &
                    ' from the low end, '//real_str(observed, 'es10.3')//' fitted')
         if (allocated(error)) return
         call setup_problem(cfg, prob3, e, exps)
         call new_effect_problem(prob3, [3], 9, base, 1.0_dp, e3, free_constants=.false., &
                                 p0=[0.0_dp, 0.0_dp, d_true])
         e3%pfree = .false.
         allocate (r1(e3%nres()), r0(e3%nres()))
         call e3%residual_at(e3%start(), r1, ok)
         e3%p0 = 0.0_dp
         if (ok) call e3%residual_at(e3%start(), r0, ok)
         call check(error, ok, 'simulations of the specimen failed')
         if (allocated(error)) return
         direct = sum((r1 - r0)**2)/(sr%f0/sr%m)
         call check(error, abs(scaled/direct - 1.0_dp) < 0.02_dp, 'drift chi-square at the injected drift: '// &
                    real_str(scaled, 'es10.3')//' from the low end, '//real_str(direct, 'es10.3')//' simulated')
         if (allocated(error)) return
         ! What the specimen could hide: the drift at the stated multiple of its low end,
         ! simulated, has the chi-square at which the rule's power is 0.95; a test is named
         ! that finds that much with power 0.95 or more
         associate (h => sr%effects(1)%hidden, q => sr%effects(1)%q)
            call check(error, h%times > 1.0_dp, 'drift: no bound of what the specimen could hide')
            if (allocated(error)) return
            e3%p0 = [0.0_dp, 0.0_dp, h%times*2.0e-5_dp/duration]
            call e3%residual_at(e3%start(), r1, ok)
            call check(error, ok, 'simulation of the specimen failed')
            if (allocated(error)) return
            direct = sum((r1 - r0)**2)/(sr%f0/sr%m)
            call check(error, abs(direct/power_lambda(0.95_dp, q, sr%m) - 1.0_dp) < 0.05_dp .and. &
                       abs(bic_power(direct, q, sr%m) - 0.95_dp) < 0.02_dp, 'drift of '// &
                       real_str(h%times, 'f0.2')//' times the low end: chi-square '//real_str(direct, 'es10.3')// &
                       ', power '//real_str(bic_power(direct, q, sr%m), 'f0.3')//' (stated 0.95)')
            if (allocated(error)) return
            call check(error, len_trim(h%test) > 0 .and. h%power >= 0.95_dp, 'no test named that finds '// &
                       'the hidden drift: '''//trim(h%test)//''', power '//real_str(h%power, 'f0.2'))
            if (allocated(error)) return
         end associate
      end block
      call check(error, all(sr%effects%power_low >= 0.0_dp), 'power not computed for every effect')
      if (allocated(error)) return
      ! 2e-5 strain over a 48 s test is below what it carries (at 0.5 % noise); a lag of
      ! 0.1 s is not
      do i = 1, size(sr%effects)
         if (sr%effects(i)%name == 'drift') call check(error, sr%effects(i)%power_low < 0.5_dp, &
            'drift power at the low end '//real_str(sr%effects(i)%power_low, 'f0.2'))
         if (sr%effects(i)%name == 'lag') call check(error, sr%effects(i)%power_low > 0.9_dp, &
            'lag power at the low end '//real_str(sr%effects(i)%power_low, 'f0.2'))
         if (allocated(error)) return
      end do
      ! Against its replicates' own misfit at their constants: the drifting specimen stands
      ! out (its objective above both of theirs), and a clean one set against the drifting
      ! one and a clean one does not: its verdict says so, and what an effect takes up is its
      ! gap, not how it differs
      call check(error, size(sr%rep_ms) == 2, 'replicates'' objectives not found')
      if (allocated(error)) return
      call check(error, own_measure(sr) > maxval(sr%rep_ms), 'the drifting specimen does not stand out: '// &
                 real_str(own_measure(sr), 'es10.3')//' against '//real_str(maxval(sr%rep_ms), 'es10.3'))
      if (allocated(error)) return
      call check(error, index(specimen_verdict(sr), 'stand out') == 0, specimen_verdict(sr))
      if (allocated(error)) return
      call specimen_run(cfg, 1, opts, .true., sr, e, exps)
      call check(error, .not. allocated(e), 'per-specimen diagnosis of the clean test failed')
      if (allocated(error)) return
      call check(error, own_measure(sr) <= sr%rep_ms(2) .and. sr%rep_ms(2) > sr%rep_ms(1), &
                 'the clean specimen against a drifting replicate: '//real_str(own_measure(sr), 'es10.3')// &
                 ' against '//real_str(sr%rep_ms(1), 'es10.3')//' and '//real_str(sr%rep_ms(2), 'es10.3'))
      if (allocated(error)) return
      call check(error, index(specimen_verdict(sr), trim(sr%name)//' does not stand out from its replicates') > 0 .and. &
                 index(specimen_verdict(sr), 'differs from its replicates') == 0, specimen_verdict(sr))
   contains
      !> The report's verdict line
      function specimen_verdict(sr) result(v)
         type(specimen_result), intent(in) :: sr
         character(len=:), allocatable :: v
         character(len=report_line_len), allocatable :: lines(:)
         integer :: k
         lines = specimen_report(sr)
         v = ''
         do k = 1, size(lines)
            if (index(lines(k), '**Verdict:**') == 1) v = trim(lines(k))
         end do
      end function specimen_verdict
   end subroutine test_specimen_drift

   !> The thesis tests with 1 % noise and no effect (data/thesis-noise1), seven constants
   !> fitted: the relaxation test set against the LCF and ratcheting tests (its first and last
   !> points weigh nothing), and the LCF test against the relaxation test alone, which leaves
   !> the cyclic constants loose (the LCF test predicted with them: objective 23 against a
   !> noise part of 1.8). Neither is a finding: each effect's BIC is set against the constants
   !> refitted to the specimen and its replicates together. (Before, relax took a drift of
   !> BIC -85.9 and the LCF test a second back stress of BIC -263.)
   subroutine test_specimen_clean(error)
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: e
      type(run_config) :: cfg
      type(diagnose_options) :: opts
      type(specimen_result) :: sr
      character(len=100), allocatable :: deck(:)
      character(len=*), parameter :: d = '../../data/thesis-noise1/'
      integer :: pass
      do pass = 1, 2
         deck = [character(len=100) :: &
            "&model temperature = 866.15, tm = 1800.0, youngs = 22.5e3, poisson = 0.3 /", &
            "&constants a1 = 0.8, a2 = 7.42e-5, b = 1.0e15, c2 = 0.1, h1 = 280.0, h2 = 100.0,", &
            "  n = 5.8, q = 91000.0 /", &
            "&fit fitted = 'A1', 'A2', 'B', 'C2', 'H1', 'H2', 'n', method = 'lm' /", &
            "&diagnose specimen = 'all' /", &
            "&test name = 'lcf', history = 'thesis_lcf', dt_out = 0.5, amp_first = 0.0005,", &
            "  amp_last = 0.005, npeaks = 12, quarter_time = 10.0, weighting = 'threshold',", &
            "  sig = 14.0, data_file = '"//d//"lcf.sim.txt' /", &
            "&test name = 'relax', history = 'relaxation', dt_out = 1.0, weighting = 'relaxation',", &
            "  levels = 0.00075, 0.001, ramp_time = 1.0, holds = 600.0, 600.0,", &
            "  data_file = '"//d//"relax.sim.txt' /"]
         if (pass == 1) deck = [character(len=100) :: deck, &
            "&test name = 'ratchet', history = 'ratchet', dt_out = 1.0, up = 0.0005, down = 0.00025,", &
            "  repeats = 15, seg_time = 40.0, data_file = '"//d//"ratchet.sim.txt' /"]
         call read_config(write_text('diag-specimen-clean.nml', deck), cfg, e)
         if (.not. allocated(e)) call diagnose_options_of(cfg, opts, e)
         if (allocated(e)) call test_failed(error, 'deck failed: '//e%message)
         if (allocated(error)) return
         call specimen_run(cfg, merge(2, 1, pass == 1), opts, .true., sr, e)
         call check(error, .not. allocated(e), 'per-specimen diagnosis failed')
         if (allocated(error)) return
         write (*, '(4x,a)') trim(sr%name)//': leading '//trim(sr%effects(1)%name)//', BIC '// &
            real_str(sr%effects(1)%dbic, 'f0.1')//'; predicted '//real_str(sr%f0, 'es9.2')//', jointly '// &
            real_str(sr%f_joint, 'es9.2')
         call check_none_significant(sr, trim(sr%name), error)
         if (allocated(error)) return
      end do
   end subroutine test_specimen_clean

   !> One specimen 5 K colder than its replicates, the low end of the temperature offset's
   !> range (independent data). Refitted from a zero offset alone, the offset stayed at
   !> -0.004 K and scatter was named; from plus and minus the low end as well, the
   !> temperature leads, with an interval that holds the injected offset
   subroutine test_specimen_temperature_low(error)
      type(error_type), allocatable, intent(out) :: error
      call specimen_low_end('data/independent-specimen-temperature-low/diagnose.nml', 'temperature', -5.0_dp, &
                            'dT', error)
   end subroutine test_specimen_temperature_low

   !> One specimen's stress read 2 % low (a load cell's calibration or its cross-section, the
   !> low end of the gain's range; independent data): the gain leads, its interval holds the
   !> injected -0.020. (scatter, with dE/E and dD0/D0 both near g, comes within BIC 10 of it
   !> and is named beside it)
   subroutine test_specimen_gain_low(error)
      type(error_type), allocatable, intent(out) :: error
      call specimen_low_end('data/independent-specimen-gain/diagnose.nml', 'gain', -0.02_dp, 'g', error)
   end subroutine test_specimen_gain_low

   !> The per-specimen diagnosis of the second test of the deck at path (independent data,
   !> one effect at the low end of its range on that specimen alone): the effect leads,
   !> significant, and the interval of its first parameter (pname) holds the injected value
   subroutine specimen_low_end(path, effect, p_true, pname, error)
      character(len=*), intent(in) :: path, effect, pname
      real(dp), intent(in) :: p_true
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: e
      type(run_config) :: cfg
      type(diagnose_options) :: opts
      type(specimen_result) :: sr
      call read_config(path, cfg, e)
      if (.not. allocated(e)) call diagnose_options_of(cfg, opts, e)
      if (.not. allocated(e)) call specimen_run(cfg, 2, opts, .true., sr, e)
      if (allocated(e)) call test_failed(error, 'per-specimen diagnosis failed: '//e%message)
      if (allocated(error)) return
      associate (lead => sr%effects(1))
         write (*, '(4x,a)') trim(sr%name)//': leading '//trim(lead%name)//', BIC '//real_str(lead%dbic, 'f0.1')
         call check(error, lead%name == effect .and. lead%significant, 'ranked first: '//trim(lead%name))
         if (allocated(error)) return
         call check(error, lead%p_lo(1) <= p_true .and. p_true <= lead%p_hi(1), &
                    pname//' '//real_str(lead%p(1), 'es10.3')//' ['//real_str(lead%p_lo(1), 'es10.3')//', '// &
                    real_str(lead%p_hi(1), 'es10.3')//'] misses '//real_str(p_true, 'es10.3'))
      end associate
   end subroutine specimen_low_end

   !> A softening shared by every test (a = 0.120, b = 200) and the held-out relaxation test
   !> 13.8 K colder besides (independent data): beside the fit tests, at the constants the
   !> data were made with and the softening carried, the relaxation test's own difference is
   !> a temperature offset, and the interval of its magnitude holds the injected one. (The
   !> diagnosis carries an effect so where it explains the fit tests but makes the held-out
   !> tests worse: see held_own in usharp_diagnose. Without it the prediction, one effect
   !> at a time, had named scatter.)
   subroutine test_specimen_carried(error)
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: e
      type(run_config) :: cfg
      type(diagnose_options) :: opts
      type(specimen_result) :: sr
      real(dp), parameter :: a_true = 0.05_dp*4.0_dp**0.63_dp, dt_true = -5.0_dp*5.0_dp**0.63_dp
      call read_config('data/independent-relax-softening-colder/diagnose.nml', cfg, e)
      if (.not. allocated(e)) call diagnose_options_of(cfg, opts, e)
      if (.not. allocated(e)) call specimen_run(cfg, 2, opts, .false., sr, e, replicates=[1, 3], &
                                                carried_k=effect_index('softening'), &
                                                carried_p=[a_true, 200.0_dp], carried_free=[.true., .true.], &
                                                carried_text='softening', peers='the fit tests')
      if (allocated(e)) call test_failed(error, 'per-specimen diagnosis failed: '//e%message)
      if (allocated(error)) return
      write (*, '(4x,a)') specimen_verdict(sr)
      call check(error, index(specimen_verdict(sr), 'temperature explains how relax differs from the fit '// &
                 'tests') == 1, specimen_verdict(sr))
      if (allocated(error)) return
      associate (lead => sr%effects(1))
         call check(error, lead%name == 'temperature' .and. lead%p_lo(1) <= dt_true .and. dt_true <= lead%p_hi(1), &
                    trim(lead%name)//' '//real_str(lead%p(1), 'f0.3')//' ['//real_str(lead%p_lo(1), 'f0.3')// &
                    ', '//real_str(lead%p_hi(1), 'f0.3')//'] misses dT '//real_str(dt_true, 'f0.3')//' K')
      end associate
   end subroutine test_specimen_carried

   !> The drift case without a drift, the specimen's data six times noisier (3 % of its peak
   !> against 0.5 %), three noise seeds: no effect is significant. Fitted with every test
   !> counting alike, such a specimen took a drift of BIC -39 that only moved the constants
   !> between the tests; the joint fits weigh each test by its points and scatter.
   subroutine test_specimen_noisier(error)
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: e
      type(run_config) :: cfg
      type(diagnose_options) :: opts
      type(experiment_type), allocatable :: exps(:)
      type(specimen_result) :: sr
      type(rng_type) :: rng
      real(dp) :: peak
      integer :: seed, i
      do seed = 1, 3
         call drift_case("'compliance', 'temperature', 'scatter', 'drift', 'softening'", 0.0_dp, 40 + seed, &
                         cfg, opts, exps, error)
         if (allocated(error)) return
         call rng%seed(70 + seed)
         peak = maxval(abs(exps(3)%y))
         do i = 1, size(exps(3)%y)
            exps(3)%y(i) = exps(3)%y(i) + 0.03_dp*peak*rng%normal()
         end do
         call specimen_run(cfg, 3, opts, .true., sr, e, exps)
         call check(error, .not. allocated(e), 'per-specimen diagnosis failed')
         if (allocated(error)) return
         write (*, '(4x,a)') 'seed '//str(seed)//': leading '//trim(sr%effects(1)%name)//', BIC '// &
            real_str(sr%effects(1)%dbic, 'f0.1')
         call check_none_significant(sr, 'seed '//str(seed), error)
         if (allocated(error)) return
      end do
   end subroutine test_specimen_noisier

   !> No effect of a per-specimen diagnosis of clean data is significant (label: the case)
   subroutine check_none_significant(sr, label, error)
      type(specimen_result), intent(in) :: sr
      character(len=*), intent(in) :: label
      type(error_type), allocatable, intent(out) :: error
      integer :: j
      do j = 1, size(sr%effects)
         call check(error, .not. sr%effects(j)%significant, label//': '//trim(sr%effects(j)%name)// &
                    ' significant in clean data, BIC '//real_str(sr%effects(j)%dbic, 'f0.1'))
         if (allocated(error)) return
      end do
   end subroutine check_none_significant

   !> Three cyclic tests (1, 0.6, 0.8 % at 1e-3/s, 3 cycles; the model's own constants) of
   !> which the third, c3, carries an extensometer drift d (1/s), 0.5 % noise (seed), and the
   !> deck that diagnoses c3 against the other two with the effects `effects`
   subroutine drift_case(effects, d, seed, cfg, opts, exps, error)
      character(len=*), intent(in) :: effects
      real(dp), intent(in) :: d
      integer, intent(in) :: seed
      type(run_config), intent(out) :: cfg
      type(diagnose_options), intent(out) :: opts
      type(experiment_type), allocatable, intent(out) :: exps(:)
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: e
      type(run_config) :: tight
      type(fit_problem) :: prob
      type(effect_problem) :: ep
      type(test_effects) :: base
      type(rng_type) :: rng
      real(dp), allocatable :: r(:), y(:)
      integer :: i, k0, n, j
      logical :: ok
      call read_config(write_text('diag-specimen.nml', [character(len=100) :: &
         "&model temperature = 866.15, tm = 1800.0, youngs = 22.5e3, poisson = 0.3 /", &
         "&constants a1 = 0.8, a2 = 7.42e-5, b = 1.0e15, c2 = 0.1, h1 = 280.0, h2 = 100.0,", &
         "  n = 5.8, q = 91000.0 /", &
         "&fit fitted = 'B', 'H1', 'n', method = 'lm' /", &
         "&diagnose specimen = 'c3', effects = "//effects//" /", &
         "&test name = 'c1', history = 'cyclic', dt_out = 0.2, strain_range = 0.01,", &
         "  strain_rate = 1.0e-3, cycles = 3 /", &
         "&test name = 'c2', history = 'cyclic', dt_out = 0.2, strain_range = 0.006,", &
         "  strain_rate = 1.0e-3, cycles = 3 /", &
         "&test name = 'c3', history = 'cyclic', dt_out = 0.2, strain_range = 0.008,", &
         "  strain_rate = 1.0e-3, cycles = 3 /"]), &
         cfg, e)
      if (.not. allocated(e)) call diagnose_options_of(cfg, opts, e)
      if (allocated(e)) call test_failed(error, 'deck failed: '//e%message)
      if (allocated(error)) return
      call placeholder_problem(cfg, prob, exps, error)
      if (allocated(error)) return
      call new_effect_problem(prob, [1, 2, 3], 9, base, 1.0_dp, ep, free_constants=.false., &
                              p0=[0.0_dp, 0.0_dp, d])
      ep%pfree = .false.
      allocate (r(ep%nres()), y(ep%nres()))
      call ep%residual_at(ep%start(), r, ok, y)
      call check(error, ok, 'simulation with drift failed')
      if (allocated(error)) return
      call rng%seed(seed)
      k0 = 0
      do i = 1, 3
         n = size(exps(i)%t)
         exps(i)%y = y(k0 + 1:k0 + n)
         do j = 1, n
            exps(i)%y(j) = exps(i)%y(j) + 0.005_dp*maxval(abs(y(k0 + 1:k0 + n)))*rng%normal()
         end do
         k0 = k0 + n
      end do
   end subroutine drift_case

   !> The power the per-specimen table states, against Monte Carlo: a drift of 2e-6/s on
   !> the drift case's c3 (an expected chi-square near the significance threshold, so that
   !> the power lies away from 0 and 1), 60 noise seeds, the constants as given; the share
   !> of repetitions in which the drift's fit is significant is the stated power (the low
   !> end's chi-square scaled to the injected drift) within 3 binomial standard errors
   subroutine test_power_monte_carlo(error)
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: e
      type(run_config) :: cfg
      type(diagnose_options) :: opts
      type(experiment_type), allocatable :: exps(:)
      type(specimen_result) :: sr
      real(dp), parameter :: d = 2.0e-6_dp
      integer, parameter :: reps = 60
      real(dp) :: stated, duration, se
      integer :: rep, found
      found = 0
      stated = 0.0_dp
      do rep = 1, reps
         call drift_case("'drift'", d, 100 + rep, cfg, opts, exps, error)
         if (allocated(error)) return
         call specimen_run(cfg, 3, opts, .false., sr, e, exps)
         call check(error, .not. allocated(e), 'per-specimen diagnosis failed')
         if (allocated(error)) return
         if (sr%effects(1)%significant) found = found + 1
         duration = maxval(exps(3)%t) - minval(exps(3)%t)
         stated = stated + bic_power(sr%effects(1)%lambda_low*(d*duration/2.0e-5_dp)**2, &
                                     sr%effects(1)%q, sr%m)/reps
      end do
      se = sqrt(max(stated*(1.0_dp - stated), 0.01_dp)/reps)
      write (*, '(4x,a)') 'power stated '//real_str(stated, 'f0.3')//', found in '//str(found)//' of '//str(reps)
      call check(error, stated > 0.2_dp .and. stated < 0.8_dp, 'the case is not near the threshold: power '// &
                 real_str(stated, 'f0.2'))
      if (allocated(error)) return
      call check(error, abs(real(found, dp)/reps - stated) <= 3.0_dp*se, 'power stated '// &
                 real_str(stated, 'f0.3')//', found in '//str(found)//' of '//str(reps))
   end subroutine test_power_monte_carlo

   !> An oscillation of 1.5 % of the peak stress and a period of 5 samples added to one cyclic
   !> test's data (model plus 0.5 % noise) is named in the verdict as serrated flow in that
   !> test, not as one of its cycles; without it the verdict names no serrated flow
   subroutine test_serrated_verdict(error)
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: e
      type(run_config) :: cfg
      type(diagnose_options) :: opts
      type(diagnose_context) :: ctx
      type(diagnose_result) :: res
      type(experiment_type), allocatable :: exps(:), clean(:)
      type(rng_type) :: rng
      real(dp), parameter :: pi = acos(-1.0_dp)
      real(dp) :: peak
      integer :: j, pass
      call model_data('diag-serrated.nml', "fitted = 'B'", 0.05_dp, 0.008_dp, 1.0e-3_dp, 3, cfg, opts, clean, &
                      error)
      if (allocated(error)) return
      call rng%seed(31)
      clean = with_noise(clean, 0.005_dp, rng)
      do pass = 1, 2
         exps = clean
         if (pass == 1) then
            peak = maxval(abs(exps(1)%y))
            exps(1)%y = exps(1)%y + 0.015_dp*peak*sin(2.0_dp*pi*[(j, j=1, size(exps(1)%y))]/5.0_dp)
         end if
         call diagnose_baseline(cfg, opts, ctx, res, e, exps)
         call check(error, .not. allocated(e), 'baseline failed')
         if (allocated(error)) return
         allocate (res%effects(0))
         call conclude(res)
         write (*, '(4x,a)') trim(merge('with   ', 'without', pass == 1))//' an oscillation: '//res%verdict
         if (pass == 1) then
            call check(error, index(res%verdict, 'serrated flow in c1') > 0 .and. &
                       index(res%verdict, 'c2 (held out): the residual') == 0, 'oscillation not named: '//res%verdict)
         else
            call check(error, index(res%verdict, 'serrated flow') == 0, 'serrated flow named in clean data: '// &
                       res%verdict)
         end if
         if (allocated(error)) return
      end do
   end subroutine test_serrated_verdict

   !> B and n fitted to 1 % cycling with 1 % noise (80 draws), 1.2 % cycling at a tenth of the
   !> rate held out without noise: its objective is the prediction's error alone, made by the
   !> scatter of the fitted constants, and averages what the constants' own uncertainty
   !> explains (pred_held, within 3 Monte Carlo standard errors), which is well above zero.
   !> The prediction's error has a long tail (in B and n's valley the largest of 80 draws is
   !> 14 times the mean uncertainty): 40 draws left the mean's standard error at 0.4 of it.
   !> Fits ending at nearly the same constants give nearly the same spread: B and n trade off,
   !> and a Jacobian at the integrator's working tolerance had left J'J's small eigenvalue to
   !> its error (the spread of one draw 2.5e-5 against 1.6e-3 from another path to the same
   !> minimum); from one draw to the next it stays within a factor 3
   subroutine test_prediction_spread(error)
      type(error_type), allocatable, intent(out) :: error
      type(run_config) :: cfg
      type(diagnose_options) :: opts
      type(diagnose_result) :: res(80)
      type(experiment_type), allocatable :: clean(:)
      real(dp) :: excess(size(res)), pred(size(res)), se, sd(2, size(res))
      integer :: k, ndraw
      call model_data('diag-spread.nml', "fitted = 'B', 'n'", 0.1_dp, 0.012_dp, 1.0e-4_dp, 1, cfg, opts, clean, &
                      error)
      if (allocated(error)) return
      call baseline_draws(cfg, opts, clean, [.true., .false.], 0.01_dp, 41, res, sd, error)
      if (allocated(error)) return
      ndraw = size(res)
      do k = 1, ndraw
         pred(k) = res(k)%pred_held
         excess(k) = res(k)%per_test0(2)
      end do
      se = sqrt(sum((excess - sum(excess)/ndraw)**2)/(ndraw - 1)/ndraw)
      write (*, '(4x,a)') 'held-out objective (prediction error) '//real_str(sum(excess)/ndraw, 'es10.3')//' +- '// &
         real_str(se, 'es9.2')//', constants'' uncertainty '//real_str(sum(pred)/ndraw, 'es10.3')
      call check(error, sum(pred)/ndraw > 3.0_dp*se .and. abs(sum(excess - pred)/ndraw) < 3.0_dp*se, &
                 'the held-out excess and the constants'' uncertainty disagree')
      if (allocated(error)) return
      call check(error, maxval(pred) < 3.0_dp*minval(pred), 'the constants'' uncertainty swings from '// &
                 real_str(minval(pred), 'es9.2')//' to '//real_str(maxval(pred), 'es9.2')//' between draws')
   end subroutine test_prediction_spread

   !> The noise of coarsely sampled cycling (1 % range at 1e-3/s, a sample every 0.5 s, 0.5 %
   !> noise, 48 draws; the held-out test 2 % at 1e-3/s): second differences of the data read
   !> the loops' knees as noise (their mean more than 5 % above it); those of the residual at
   !> the baseline, the diagnosis's estimate, come within 2 %
   subroutine test_residual_noise(error)
      type(error_type), allocatable, intent(out) :: error
      type(run_config) :: cfg
      type(diagnose_options) :: opts
      type(diagnose_result) :: res(48)
      type(experiment_type), allocatable :: clean(:)
      real(dp) :: from_data(2), from_residual(2), truth(2), sd(2, size(res))
      character(len=120) :: buf
      integer :: k, i
      call model_data('diag-noise.nml', "fitted = 'B', 'n'", 0.5_dp, 0.02_dp, 1.0e-3_dp, 3, cfg, opts, clean, &
                      error)
      if (allocated(error)) return
      call baseline_draws(cfg, opts, clean, [.true., .true.], 0.005_dp, 43, res, sd, error)
      if (allocated(error)) return
      truth = [(0.005_dp*maxval(abs(clean(i)%y)), i=1, 2)]
      from_data = sum(sd, 2)/size(res)/truth
      from_residual = 0.0_dp
      do k = 1, size(res)
         from_residual = from_residual + res(k)%noise/truth/size(res)
      end do
      write (buf, '(a,2f7.3,a,2f7.3)') 'noise estimate over the truth (fitted, held out): data', &
         from_data, ', residual', from_residual
      write (*, '(4x,a)') trim(buf)
      call check(error, all(from_data > 1.05_dp), 'the data''s curvature reads as noise: '//trim(buf))
      if (allocated(error)) return
      call check(error, all(abs(from_residual - 1.0_dp) < 0.02_dp), trim(buf))
   end subroutine test_residual_noise

   !> The baseline of each of size(res) draws of Gaussian noise (sd rel times the test's peak)
   !> on the tests of clean marked noisy, the others as they are (rng seeded with seed); sd:
   !> each test's noise estimated from its data alone (noise_sd), per draw
   subroutine baseline_draws(cfg, opts, clean, noisy, rel, seed, res, sd, error)
      type(run_config), intent(in) :: cfg
      type(diagnose_options), intent(in) :: opts
      type(experiment_type), intent(in) :: clean(:)
      logical, intent(in) :: noisy(:)
      real(dp), intent(in) :: rel
      integer, intent(in) :: seed
      type(diagnose_result), intent(out) :: res(:)
      real(dp), intent(out) :: sd(:, :)
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: e
      type(diagnose_context) :: ctx
      type(experiment_type), allocatable :: exps(:)
      type(rng_type) :: rng
      integer :: k, i
      call rng%seed(seed)
      do k = 1, size(res)
         exps = clean
         do i = 1, size(clean)
            if (noisy(i)) exps(i:i) = with_noise(clean(i:i), rel, rng)
            sd(i, k) = noise_sd(exps(i)%y)
         end do
         call diagnose_baseline(cfg, opts, ctx, res(k), e, exps)
         call check(error, .not. allocated(e), 'baseline failed')
         if (allocated(error)) return
      end do
   end subroutine baseline_draws

   !> A deck of two cyclic tests (c1: 1 % range at 1e-3/s, 3 cycles, fitted; c2 held out:
   !> range2 at rate2, cycles2) sampled every dt s, the Table 4 constants, &fit's list of
   !> constants fit; clean holds each test's response of the plain model at its output times,
   !> integrated at rtol 1e-10 (made at the fit's own tolerance, the data held its integration
   !> error, which a fit starting at these constants then met exactly there and nowhere else:
   !> some fits of noisy data stayed at the start, in a well of that error, not the noise's)
   subroutine model_data(name, fit, dt, range2, rate2, cycles2, cfg, opts, clean, error)
      character(len=*), intent(in) :: name, fit
      real(dp), intent(in) :: dt, range2, rate2
      integer, intent(in) :: cycles2
      type(run_config), intent(out) :: cfg
      type(diagnose_options), intent(out) :: opts
      type(experiment_type), allocatable, intent(out) :: clean(:)
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: e
      type(run_config) :: tight
      type(fit_problem) :: prob
      type(effect_problem) :: ep
      type(test_effects) :: base
      real(dp), allocatable :: r(:), y(:)
      integer :: i, k0, n
      logical :: ok
      call read_config(write_text(name, [character(len=100) :: &
         "&model temperature = 866.15, tm = 1800.0, youngs = 22.5e3, poisson = 0.3 /", &
         "&constants a1 = 0.8, a2 = 7.42e-5, b = 1.0e15, c2 = 0.1, h1 = 280.0, h2 = 100.0,", &
         "  n = 5.8, q = 91000.0 /", &
         "&fit "//fit//", method = 'lm' /", &
         "&diagnose holdout = 'c2' /", &
         "&test name = 'c1', history = 'cyclic', dt_out = "//real_str(dt, 'f0.3')//", strain_range = 0.01,", &
         "  strain_rate = 1.0e-3, cycles = 3 /", &
         "&test name = 'c2', history = 'cyclic', dt_out = "//real_str(dt, 'f0.3')//", strain_range = "// &
         real_str(range2, 'f0.4')//",", "  strain_rate = "//real_str(rate2, 'es8.1')//", cycles = "// &
         str(cycles2)//" /"]), cfg, e)
      if (.not. allocated(e)) call diagnose_options_of(cfg, opts, e)
      if (allocated(e)) call test_failed(error, 'deck failed: '//e%message)
      if (allocated(error)) return
      tight = cfg
      tight%solver%rtol = 1.0e-10_dp
      tight%solver%atol_strain = 1.0e-14_dp
      call placeholder_problem(tight, prob, clean, error)
      if (allocated(error)) return
      call new_effect_problem(prob, [1, 2], 1, base, 1.0_dp, ep, free_constants=.false., p0=[0.0_dp])
      allocate (r(ep%nres()), y(ep%nres()))
      call ep%residual_at(ep%start(), r, ok, y)
      call check(error, ok, 'simulation failed')
      if (allocated(error)) return
      k0 = 0
      do i = 1, 2
         n = size(clean(i)%t)
         clean(i)%y = y(k0 + 1:k0 + n)
         k0 = k0 + n
      end do
   end subroutine model_data

   !> Each test's data with Gaussian noise of sd rel times its peak added
   function with_noise(clean, rel, rng) result(exps)
      type(experiment_type), intent(in) :: clean(:)
      real(dp), intent(in) :: rel
      type(rng_type), intent(inout) :: rng
      type(experiment_type), allocatable :: exps(:)
      integer :: i, j
      exps = clean
      do i = 1, size(exps)
         exps(i)%y = [(clean(i)%y(j) + rel*maxval(abs(clean(i)%y))*rng%normal(), j=1, size(clean(i)%y))]
      end do
   end function with_noise

   !> Data made by a program that is not usharp (bench/independent: Python, scipy's Radau)
   !> for the thesis matrix with the ratcheting test held out, 0.5 % noise: clean data give
   !> no significant effect; a modulus drop of 5.5 % shared by every test (which no catalogue
   !> effect is exactly, compliance is the same for these tests) is named compliance or
   !> scatter, removing >= 80 % of the held-out gap; a temperature offset of 11 K shared by
   !> every test with D0 at its nominal value leads as temperature or initial (a drag offset:
   !> the common part of dT goes into B theta), or is named as explaining the gap equally well
   !> with a separating test proposed, removing >= 80 % of the held-out gap (the data:
   !> data/independent-ratchet-*, bench/independent/test-data.sh).
   subroutine test_independent(error)
      type(error_type), allocatable, intent(out) :: error
      type(diagnose_result) :: res
      character(len=16), parameter :: rows(3) = [character(len=16) :: 'clean', 'modulus', 'temperature']
      logical :: named
      integer :: i, j
      do i = 1, size(rows)
         call diagnose_deck('data/independent-ratchet-'//trim(rows(i))//'/diagnose.nml', res, error)
         if (allocated(error)) return
         write (*, '(4x,a)') trim(rows(i))//': '//res%verdict
         if (rows(i) == 'clean') then
            call check(error, res%leading == 0 .and. index(res%verdict, 'no significant effect') == 1, &
                       'clean data: '//res%verdict)
            if (allocated(error)) return
            ! The power statement: computed for every effect; the LCF and relaxation tests
            ! find a compliance, a lag and a temperature offset at the low end of their
            ! ranges (as the independent table's low-end repetitions do, 6 of 6 each)
            call check(error, all(res%effects%power_low >= 0.0_dp .and. res%effects%power_low <= 1.0_dp), &
                       'power not computed for every effect')
            if (allocated(error)) return
            do j = 1, size(res%effects)
               if (any(res%effects(j)%name == ['compliance ', 'lag        ', 'temperature'])) &
                  call check(error, res%effects(j)%power_low > 0.9_dp, 'power against '// &
                             trim(res%effects(j)%name)//' at its low end: '//real_str(res%effects(j)%power_low, 'f0.2'))
               if (allocated(error)) return
            end do
         else if (rows(i) == 'modulus') then
            call check(error, res%leading > 0, 'modulus drop: no effect confirmed')
            if (allocated(error)) return
            call check(error, any(res%effects(res%leading)%name == ['compliance', 'scatter   ']) .and. &
                       res%effects(res%leading)%shrink_held >= 0.8_dp, 'modulus drop: '//res%verdict)
         else
            call check(error, res%leading > 0, 'temperature offset: no effect confirmed')
            if (allocated(error)) return
            named = any(res%effects(res%leading)%name == ['temperature', 'initial    '])
            do j = 1, size(res%alike)
               named = named .or. (any(res%effects(res%alike(j))%name == ['temperature', 'initial    ']) .and. &
                                   size(res%seps) > 0)
            end do
            call check(error, named .and. res%effects(res%leading)%shrink_held >= 0.8_dp, &
                       'temperature offset: '//res%verdict)
         end if
         if (allocated(error)) return
      end do
   end subroutine test_independent

   !> A softening (a = 0.076, independent data) in all three thesis tests with the LCF test
   !> held out: relaxation and ratcheting show no structured gap, so no prediction from them
   !> confirms anything; fitted together with the LCF test, softening is named, the verdict
   !> saying on what evidence
   subroutine test_joint(error)
      type(error_type), allocatable, intent(out) :: error
      type(diagnose_result) :: res
      call diagnose_deck('data/independent-lcf-softening/diagnose.nml', res, error)
      if (allocated(error)) return
      write (*, '(4x,a)') res%verdict
      call check(error, res%leading == 0 .and. allocated(res%joint), &
                 'the fit tests'' prediction confirmed an effect, or no joint stage ran')
      if (allocated(error)) return
      call check(error, named_effect(res) == effect_index('softening') .and. &
                 index(res%verdict, 'softening (fitted with the held-out tests') == 1, res%verdict)
   end subroutine test_joint

   !> A softening (a = 0.107, b = 200, independent data) with the relaxation test held out:
   !> the screening's shortest runs on LCF and ratcheting end as a hardening, and refitted
   !> from there alone it came out as a = -0.31, b = 42, which mispredicted the relaxation
   !> (nothing confirmed, the effect's form left to every test fitted together). Refitted from
   !> the best end point of each sign, the softening is found with its magnitude and confirmed
   !> by the prediction of the held-out test. The prediction is open between end points the
   !> fit tests cannot tell apart (81 to 97 % of the held-out gap): the same case made where
   !> libm takes its FMA paths (data 3e-10 apart) ends at a point that carries 44 %, and every
   !> test fitted together names the softening. Hence data kept in data/ (see
   !> bench/independent/test-data.sh), not made anew on each machine. The diagnosis's last
   !> step names the candidate test that tells the two end points carrying the least and the
   !> most of the held-out gap apart: two distinct points, the candidate of the largest
   !> expected chi-square difference, named in the verdict where it reaches significance.
   !> The catalogue's first nine effects only: with the stress-channel gain as well, its
   !> refit's constants start a baseline that runs to B's bound and is lower, from which the
   !> softening is found as here (a = 0.103 [0.096, 0.110]) but carries 99.1 % of the
   !> held-out gap, not open
   subroutine test_softening_sign(error)
      type(error_type), allocatable, intent(out) :: error
      type(diagnose_result) :: res
      real(dp), parameter :: a_true = 0.05_dp*4.0_dp**0.55_dp, b_true = 200.0_dp
      type(uerror), allocatable :: e
      type(run_config) :: cfg
      type(diagnose_options) :: opts
      call read_config('data/independent-relax-softening/diagnose.nml', cfg, e)
      if (.not. allocated(e)) then
         cfg%diagnose%effects(1:9) = [character(len=len(cfg%diagnose%effects)) :: 'compliance', 'lag', &
            'temperature', 'scatter', 'initial', 'shift', 'softening', 'backstress2', 'drift']
         call diagnose_options_of(cfg, opts, e)
      end if
      if (.not. allocated(e)) call diagnose_run(cfg, opts, res, e)
      if (allocated(e)) call test_failed(error, 'diagnosis failed: '//e%message)
      if (allocated(error)) return
      write (*, '(4x,a)') res%verdict
      call check(error, res%leading > 0 .and. named_effect(res) == effect_index('softening') .and. &
                 .not. joint_decides(res), 'softening not confirmed by the prediction: '//res%verdict)
      if (allocated(error)) return
      associate (e => res%effects(res%leading))
         write (*, '(4x,a)') 'a = '//real_str(e%p(1), 'es10.3')//' ['//real_str(e%p_lo(1), 'es10.3')//', '// &
            real_str(e%p_hi(1), 'es10.3')//'], b = '//real_str(e%p(2), 'es10.3')//' ['// &
            real_str(e%p_lo(2), 'es10.3')//', '//real_str(e%p_hi(2), 'es10.3')//']'
         call check(error, e%p_lo(1) <= a_true .and. a_true <= e%p_hi(1) .and. &
                    e%p_lo(2) <= b_true .and. b_true <= e%p_hi(2), &
                    'the injected a = '//real_str(a_true, 'f0.3')//', b = 200 outside the 95 % intervals')
         if (allocated(error)) return
         call check(error, prediction_open(e) .and. allocated(e%c_open) .and. res%pin%best > 0, &
                    'the open prediction has no candidate test: '//res%verdict)
         if (allocated(error)) return
         write (*, '(4x,a,5es10.2)') 'D of the candidates between the end points:', res%pin%d
         call check(error, any(e%c_open(:, 1) /= e%c_open(:, 2)) .or. any(e%p_open(:, 1) /= e%p_open(:, 2)), &
                    'the end points that carry the least and the most of the held-out gap are one point')
         if (allocated(error)) return
         call check(error, res%pin%d(res%pin%best) == maxval(res%pin%d) .and. res%pin%d(res%pin%best) >= separating_d &
                    .and. index(res%verdict, 'a '//trim(res%pin%names(res%pin%best))// &
                    ' would tell those end points apart') > 0, 'the best candidate not named: '//res%verdict)
      end associate
   end subroutine test_softening_sign

   !> A second back stress of 1 ksi (independent data) with the LCF test held out: relaxation
   !> and ratcheting show no structured gap and leave the constants loose, so refits of a
   !> delay of 6.55 ms, a compliance and a softening wandered to constants that predict the
   !> LCF test by themselves (100 % of its gap without the effect) and were "confirmed"; a lag
   !> below the sampling interval then led. Such a prediction is no evidence. Where a refit's
   !> constants alone fit the fit tests better than the baseline (with the relaxation weights
   !> from the raw differences of the data, the compliance's: 0.689 -> 0.678), the baseline is
   !> fitted again from them; either way no refit leaves the final baseline behind, no delay or
   !> compliance is significant against it, nothing is confirmed on the fit tests, and every
   !> test fitted together names the second back stress. (Where the baseline stays, judge's
   !> carried_by_constants is what refuses such a prediction: test
   !> prediction-of-loose-constants-confirms-nothing.)
   subroutine test_loose_constants(error)
      type(error_type), allocatable, intent(out) :: error
      type(diagnose_result) :: res
      integer :: j
      call diagnose_deck('data/independent-lcf-backstress2-low/diagnose.nml', res, error)
      if (allocated(error)) return
      write (*, '(4x,a)') res%verdict
      call check(error, res%leading == 0 .and. .not. any(res%effects%confirmed), &
                 'an effect confirmed by the held-out prediction of loose constants: '//res%verdict)
      if (allocated(error)) return
      write (*, '(4x,a,l1)') 'baseline fitted again from a refit''s constants: ', allocated(res%rebased_by)
      call check(error, baseline_left_behind(res) == 0, 'a refit''s constants alone fit the fit tests '// &
                 'better than the baseline every effect is judged against')
      if (allocated(error)) return
      do j = 1, size(res%effects)
         associate (e => res%effects(j))
            if (any(e%k == [effect_index('shift'), effect_index('lag'), effect_index('compliance')])) then
               call check(error, .not. e%significant, trim(e%name)//': '//verdict_of(e, res))
               if (allocated(error)) return
            end if
         end associate
      end do
      call check(error, named_effect(res) == effect_index('backstress2'), res%verdict)
   end subroutine test_loose_constants

   !> A drift at the low end of its range, strongest in one fit test (independent data: 2e-5
   !> strain over each test, -8.3e-8 1/s in the LCF test; ratcheting held out): on the fit
   !> tests the constants take it up. The power the verdict states against a per-test effect
   !> is the least over the fit tests together and each alone: with the drift at its low end
   !> in both fit tests the power was 1.00 and the verdict said nothing of a drift it had
   !> missed; it is now below 0.95, with the multiple of the low end at which it would be
   !> found holding the injected one (1.0). The verdict then names the drift as one the fit
   !> tests could miss, or, where an effect of the fit tests sends the diagnosis on to every
   !> test fitted together (a temperature offset at BIC -12.8 on them, their gaps below the
   !> floors, as the last bits of the baseline's search decide), names the drift found there;
   !> no other effect
   subroutine test_drift_one_test(error)
      type(error_type), allocatable, intent(out) :: error
      type(diagnose_result) :: res
      integer :: j
      call diagnose_deck('data/independent-ratchet-drift-low/diagnose.nml', res, error)
      if (allocated(error)) return
      write (*, '(4x,a)') res%verdict
      call check(error, named_effect(res) == 0 .or. named_effect(res) == effect_index('drift'), &
                 'an effect other than the drift named: '//res%verdict)
      if (allocated(error)) return
      j = findloc(res%effects%k, effect_index('drift'), 1)
      call check(error, j > 0, 'drift not screened')
      if (allocated(error)) return
      write (*, '(4x,a)') 'drift: power at the low end '//real_str(res%effects(j)%power_low, 'f0.2')// &
         ', found with power 0.95 from '//real_str(res%effects(j)%hidden%times, 'f0.2')//' times it'
      call check(error, res%effects(j)%power_low < 0.95_dp .and. res%effects(j)%hidden%times >= 1.0_dp, &
                 'drift at the low end in one fit test: power '//real_str(res%effects(j)%power_low, 'f0.2')// &
                 ', hidden up to '//real_str(res%effects(j)%hidden%times, 'f0.2')//' times the low end')
      if (allocated(error)) return
      if (named_effect(res) == 0) call check(error, index(res%verdict, 'could miss: ') > 0 .and. &
                                             index(res%verdict, 'drift (power') > 0, &
                                             'the verdict does not name the drift as one it could miss: '//res%verdict)
   end subroutine test_drift_one_test

   !> A fast second back stress (independent data: H3/gamma3 1.55 ksi at gamma3 = 1266; the
   !> LCF test held out): its screening runs start from recovery rates half, twice, ten and
   !> fifty times the screening's 200 (backstress2_starts) and its refit from the lowest end point
   !> of each rate's (rate_rungs); from gamma3 = 200 alone the refit stayed in that rate's basin
   !> and a softening was named. The second back stress is named, with an interval of gamma3
   !> that holds the injected one
   subroutine test_fast_backstress(error)
      type(error_type), allocatable, intent(out) :: error
      type(diagnose_result) :: res
      call diagnose_deck('data/independent-lcf-backstress2-fast/diagnose.nml', res, error)
      if (allocated(error)) return
      write (*, '(4x,a)') res%verdict
      call check_gamma3(res, 1266.0_dp, error)
   end subroutine test_fast_backstress

   !> A fast second back stress (independent data: H3/gamma3 1.38 ksi at gamma3 = 4898; the
   !> LCF test held out) whose baseline, one start, converges at an objective of 2.42 on the
   !> fit tests, where refits of effects that do next to nothing (a delay of 7 ms, a machine
   !> compliance) end at 0.64 with their constants alone as low: a shift was named. Such a
   !> refit shows that the baseline was not the optimum of the constants
   !> (baseline_left_behind): the baseline is fitted again from its constants and ends lower
   !> (below 0.7), the delay and the compliance are not significant against it, and the
   !> second back stress is named with an interval of gamma3 that holds the injected one.
   !> Every candidate is refitted (n_refit = 9): which of them screening puts among the
   !> three refitted by default follows the baseline's end point, which the last bits of the
   !> arithmetic steer (from a baseline at 2.19 the three leaders' refits, each with its
   !> effect, show no better basin of the constants alone)
   subroutine test_baseline_left_behind(error)
      type(error_type), allocatable, intent(out) :: error
      type(diagnose_result) :: res
      type(run_config) :: cfg
      type(diagnose_options) :: opts
      type(uerror), allocatable :: e
      integer :: j
      call read_config('data/independent-lcf-backstress2-basin/diagnose.nml', cfg, e)
      if (.not. allocated(e)) then
         cfg%diagnose%n_refit = n_effects
         call diagnose_options_of(cfg, opts, e)
      end if
      if (.not. allocated(e)) call diagnose_run(cfg, opts, res, e)
      if (allocated(e)) then
         call test_failed(error, 'diagnosis failed: '//e%message)
         return
      end if
      write (*, '(4x,a)') res%verdict
      write (*, '(4x,a,2es12.4)') 'first baseline, baseline:', res%f0_left, res%f0
      call check(error, allocated(res%rebased_by), 'the baseline was not fitted again')
      if (allocated(error)) return
      call check(error, res%f0_left > 2.0_dp .and. res%f0 < 0.7_dp, 'the baseline fitted again did not end lower')
      if (allocated(error)) return
      do j = 1, size(res%effects)
         if (res%effects(j)%k == effect_index('shift') .or. res%effects(j)%k == effect_index('compliance')) then
            call check(error, .not. res%effects(j)%significant, trim(res%effects(j)%name)// &
                       ' still significant against the baseline fitted again')
            if (allocated(error)) return
         end if
      end do
      call check_gamma3(res, 4898.0_dp, error)
   end subroutine test_baseline_left_behind

   !> The baseline's search goes on past its iteration limit while it still descends (see
   !> converge_baseline): the search of the baseline of data/independent-lcf-backstress2-basin
   !> from the deck's constants, cut at its iteration limit (here `cut`) while it descends, is
   !> continued from there in rounds of lm_itermax iterations until it converges, lower than
   !> where it was cut. (Whether a search from the deck's constants reaches lm_itermax itself
   !> depends on its path, which the last bits of the arithmetic decide: cut here, it does.)
   subroutine test_baseline_continued(error)
      type(error_type), allocatable, intent(out) :: error
      integer, parameter :: cut = 10
      type(run_config) :: cfg
      type(diagnose_options) :: opts
      type(diagnose_context) :: ctx
      type(diagnose_result) :: res, cont
      type(effect_problem) :: base
      type(optimum_type) :: opt
      type(uerror), allocatable :: e
      real(dp), allocatable :: lo(:), hi(:), x0(:)
      real(dp) :: f_cut
      integer :: j
      call read_config('data/independent-lcf-backstress2-basin/diagnose.nml', cfg, e)
      if (.not. allocated(e)) call diagnose_options_of(cfg, opts, e)
      if (.not. allocated(e)) call diagnose_baseline(cfg, opts, ctx, res, e)
      if (allocated(e)) then
         call test_failed(error, 'baseline failed: '//e%message)
         return
      end if
      call new_effect_problem(ctx%prob, ctx%ifit, 0, ctx%eff_base, ctx%peak, base)
      call base%bounds(lo, hi)
      x0 = [(log10(cfg%model%get_constant(ctx%prob%idx(j))), j=1, size(ctx%prob%idx))]
      call levenberg_marquardt(base, min(max(x0, lo), hi), lo, hi, ctx%h, lm_ftol, cut, opts%max_evals, &
                               opt, e, updates=lm_updates)
      if (allocated(e)) then
         call test_failed(error, 'search failed: '//e%message)
         return
      end if
      f_cut = opt%f
      call check(error, opt%reason == reason_itermax, 'the search converged within '//str(cut)//' iterations')
      if (allocated(error)) return
      call converge_baseline(ctx, base, lo, hi, opt, cont, e)
      if (allocated(e)) then
         call test_failed(error, 'continuation failed: '//e%message)
         return
      end if
      write (*, '(4x,a,i0,a,es12.5,a,i0,a,es12.5)') 'cut at ', cut, ' iterations: ', f_cut, '; continued: ', &
         cont%baseline_iterations, ' iterations, ', opt%f
      call check(error, cont%baseline_iterations > cut .and. cont%baseline_converged, &
                 'the search was not continued to convergence: '//str(cont%baseline_iterations)//' iterations')
      if (allocated(error)) return
      call check(error, opt%f < f_cut, 'the continued search did not descend: '//real_str(opt%f, 'es12.5'))
   end subroutine test_baseline_continued

   !> The thesis tests with 1 % noise and no effect (data/thesis-noise1), the relaxation test
   !> logged every 10 s instead of every second (dt_out = 1 s, as the deck asks). Compared at
   !> values interpolated between its samples, its residual had no noise to speak of (1e-5 of
   !> the peak) and an initial state was named (BIC -844); compared at its samples, its noise
   !> is the data's and nothing is named, and the report says what was left out
   subroutine test_coarse_log(error)
      type(error_type), allocatable, intent(out) :: error
      type(diagnose_result) :: res
      character(len=:), allocatable :: text, line, last, f
      character(len=220), allocatable :: rows(:), deck(:)
      character(len=*), parameter :: d = '../../data/thesis-noise1/'
      integer :: i, j, n
      text = read_text('data/thesis-noise1/relax.sim.txt')
      allocate (rows(0))
      n = 0
      i = 1
      last = ''
      do
         j = index(text(i:), new_line('a'))
         if (j == 0) exit
         line = text(i:i + j - 2)
         i = i + j
         if (line(1:1) == '#') then
            rows = [character(len=220) :: rows, line]
            cycle
         end if
         n = n + 1
         last = line
         if (mod(n - 1, 10) == 0) rows = [character(len=220) :: rows, line]
         if (mod(n - 1, 10) == 0) last = ''
      end do
      if (len(last) > 0) rows = [character(len=220) :: rows, last]
      f = write_text('relax-every-10s.sim.txt', rows)
      deck = [character(len=220) :: &
         "&model temperature = 866.15, tm = 1800.0, youngs = 22.5e3, poisson = 0.3 /", &
         "&constants a1 = 0.8, a2 = 7.42e-5, b = 1.0e15, c2 = 0.1, h1 = 280.0, h2 = 100.0, n = 5.8, q = 91000.0 /", &
         "&fit fitted = 'A1', 'A2', 'B', 'C2', 'H1', 'H2', 'n', method = 'lm', objective = 'eq7' /", &
         "&diagnose holdout = 'ratchet' /", &
         "&test name = 'lcf', history = 'thesis_lcf', dt_out = 0.5, amp_first = 0.0005, amp_last = 0.005,", &
         "  npeaks = 12, quarter_time = 10.0, weighting = 'threshold', sig = 14.0, data_file = '"//d//"lcf.sim.txt' /", &
         "&test name = 'relax', history = 'relaxation', dt_out = 1.0, weighting = 'relaxation',", &
         "  levels = 0.00075, 0.001, ramp_time = 1.0, holds = 600.0, 600.0, data_file = 'relax-every-10s.sim.txt' /", &
         "&test name = 'ratchet', history = 'ratchet', dt_out = 1.0, up = 0.0005, down = 0.00025,", &
         "  repeats = 15, seg_time = 40.0, data_file = '"//d//"ratchet.sim.txt' /"]
      call diagnose_deck(write_text('diag-coarse-log.nml', deck), res, error)
      if (allocated(error)) return
      write (*, '(4x,a)') 'relax noise '//real_str(100.0_dp*res%noise(2)/res%peak(2), 'f0.2')//' % of its peak; '// &
         trim(res%data_notes(2))
      call check(error, res%noise(2) > 0.005_dp*res%peak(2), 'the noise of the relaxation test is its data''s (1 %)')
      if (allocated(error)) return
      call check(error, index(res%data_notes(2), 'not compared: 1081') > 0, 'what was left out: '//trim(res%data_notes(2)))
      if (allocated(error)) return
      call check(error, res%leading == 0 .and. index(res%verdict, 'no significant effect') == 1, &
                 'nothing named: '//res%verdict)
   end subroutine test_coarse_log

   !> Clean independent data with the relaxation test held out
   !> (data/independent-relax-clean-joint). With the relaxation weights from the raw
   !> differences of the noisy data, its predicted gap (within what the constants'
   !> uncertainty explains) sent the diagnosis on to every test fitted together, where a
   !> compliance refit's constants fit every test better than that stage's first baseline (a
   !> compliance had been named there at BIC -13); that stage's baseline is now fitted again
   !> from them, as the fit tests' is (one procedure for both stages; the fit tests' case:
   !> baseline-left-behind-is-fitted-again). With the weights from the smoothed data the
   !> held-out gap lies below its floor and that stage does not run. Either way nothing is
   !> named, and where the stage runs, no refit's constants leave its baseline behind
   subroutine test_joint_rebaseline(error)
      type(error_type), allocatable, intent(out) :: error
      type(diagnose_result) :: res
      call diagnose_deck('data/independent-relax-clean-joint/diagnose.nml', res, error)
      if (allocated(error)) return
      write (*, '(4x,a)') res%verdict
      call check(error, res%leading == 0 .and. index(res%verdict, 'no significant effect') == 1, &
                 'clean data: '//res%verdict)
      if (allocated(error)) return
      if (.not. allocated(res%joint)) return
      write (*, '(4x,a,l1)') 'every test fitted; its baseline fitted again: ', allocated(res%joint%rebased_by)
      call check(error, res%joint%leading == 0 .and. baseline_left_behind(res%joint) == 0, &
                 'every test fitted: an effect named, or its baseline left behind')
   end subroutine test_joint_rebaseline

   !> A temperature offset of +17.2 K in every test (independent data,
   !> data/independent-lcf-temperature-joint; the LCF test held out). Relaxation and
   !> ratcheting leave the constants too loose for the prediction of the LCF test to confirm
   !> the temperature that leads on them, so every test is fitted together. That stage's
   !> baseline takes up what it can of the offset in the constants, and from there and its
   !> further starts the temperature refit ended at 3.28 (39.7 % of the gap, 9.5, -0.9 and
   !> 1.4 K), while a softening (b at its bound) reached 1.07 and was named. The fit tests'
   !> own temperature refit, with the LCF test's value fitted to it, lies far below that
   !> (1.071) and the refit now goes on from there: it reaches the injected offset in every
   !> test (each 95 % interval holds 17.2 K),
   !> removes the whole gap, and the verdict names the temperature or the initial state it
   !> cannot be told from with the test that would tell them apart
   subroutine test_joint_carried(error)
      type(error_type), allocatable, intent(out) :: error
      type(diagnose_result) :: res
      real(dp), parameter :: dt_true = 17.2_dp
      integer :: j, g
      call diagnose_deck('data/independent-lcf-temperature-joint/diagnose.nml', res, error)
      if (allocated(error)) return
      write (*, '(4x,a)') res%verdict
      call check(error, allocated(res%joint), 'no stage with every test fitted: '//res%verdict)
      if (allocated(error)) return
      do j = 1, size(res%joint%effects)
         associate (e => res%joint%effects(j))
            if (e%k /= effect_index('temperature')) cycle
            call check(error, e%refitted, 'every test fitted: temperature not refitted')
            if (allocated(error)) return
            write (*, '(4x,a,3f8.2,a,f6.1,a)') 'every test fitted, temperature: dT', e%p, ' K, gap removed ', &
               100*e%shrink_fit, ' %'
            do g = 1, size(e%p)
               call check(error, e%p_lo(g) <= dt_true .and. dt_true <= e%p_hi(g), trim(e%pname(g))//' = '// &
                          real_str(e%p(g), 'f0.2')//' K: its 95 % interval misses the injected 17.2 K')
               if (allocated(error)) return
            end do
            call check(error, e%shrink_fit >= 0.95_dp, 'every test fitted: the temperature refit removed '// &
                       real_str(100*e%shrink_fit, 'f0.1')//' % of the gap')
            if (allocated(error)) return
         end associate
      end do
      call check(error, named_effect(res) == effect_index('temperature') .or. &
                 (named_effect(res) == effect_index('initial') .and. &
                  index(res%verdict, 'would tell initial from temperature') > 0), res%verdict)
      if (allocated(error)) return
      ! Each refit's initial drag stress, which the report gives beside an initial drag
      ! offset: the deck's model set up at the refit's constants has that D0
      block
         type(run_config) :: cfg
         type(uerror), allocatable :: e
         type(miller_model) :: m
         integer, allocatable :: idx(:)
         integer :: k, nchecked
         call read_config('data/independent-lcf-temperature-joint/diagnose.nml', cfg, e)
         call check(error, .not. allocated(e), 'deck not read')
         if (allocated(error)) return
         select type (mm => cfg%model)
         type is (miller_model)
            m = mm
         end select
         idx = pack([(k, k=1, size(cfg%fit%fitted))], cfg%fit%fitted)
         nchecked = 0
         do k = 1, size(res%effects)
            if (.not. (res%effects(k)%refitted .and. allocated(res%effects(k)%c))) cycle
            do j = 1, size(idx)
               call m%set_constant(idx(j), res%effects(k)%c(j))
            end do
            call model_setup(m, e)
            if (allocated(e)) cycle
            call check(error, abs(res%effects(k)%drag0 - m%d0) <= 1.0e-12_dp*m%d0, trim(res%effects(k)%name)// &
                       ': D0 '//real_str(res%effects(k)%drag0, 'es14.7')//' against '//real_str(m%d0, 'es14.7'))
            if (allocated(error)) return
            nchecked = nchecked + 1
         end do
         call check(error, nchecked > 0, 'no refit to check D0 on')
      end block
   end subroutine test_joint_carried

   !> A softening of a = 0.093 (independent data, data/independent-creep-softening-open; the
   !> creep test held out). Cycling and relaxation fix the softening's start (a b) but not
   !> its saturation a, which the long creep test reaches: the refit's starts end at 8 points
   !> the fit tests cannot tell apart (BIC within 10), carrying 70.9 to 100 % of the held-out
   !> gap one by one, and the lowest on the fit tests carried least. The prediction is their
   !> responses weighted by the fit tests (exp(-deviance/2)): it removes 80 % or more of the
   !> held-out gap where the lowest end point alone removed 70.9 %, and the verdict gives
   !> that share, the range and the test that would tell the end points apart
   subroutine test_open_weighted(error)
      type(error_type), allocatable, intent(out) :: error
      type(diagnose_result) :: res
      call diagnose_deck('data/independent-creep-softening-open/diagnose.nml', res, error)
      if (allocated(error)) return
      write (*, '(4x,a)') res%verdict
      call check(error, res%leading > 0 .and. named_effect(res) == effect_index('softening'), &
                 'softening not named: '//res%verdict)
      if (allocated(error)) return
      associate (e => res%effects(res%leading))
         write (*, '(4x,a,i0,a,4f7.1)') 'held-out gap removed: weighted over ', e%n_alike + 1, &
            ' end points, the one used alone, least, most (%):', 100*e%shrink_held, 100*e%shrink_held_point, &
            100*e%shrink_alike_lo, 100*e%shrink_alike_hi
         call check(error, prediction_open(e) .and. e%shrink_held >= 0.8_dp .and. &
                    e%shrink_held > e%shrink_held_point, 'the held-out prediction removed '// &
                    real_str(100*e%shrink_held, 'f0.1')//' % (the end point used alone '// &
                    real_str(100*e%shrink_held_point, 'f0.1')//' %)')
         if (allocated(error)) return
         call check(error, index(res%verdict, real_str(100*e%shrink_held, 'f0.1')//' % on the held-out tests') > 0 &
                    .and. index(res%verdict, 'would tell those end points apart') > 0, res%verdict)
      end associate
   end subroutine test_open_weighted

   !> Extensometer drifts of 8.3e-8, 1.7e-8 and -1.7e-8 1/s (independent data,
   !> data/independent-drift; the relaxation test held out): the walks of the leading drift's
   !> profile meet points below its refit's end point (0.70661 -> 0.70643 on the fit tests),
   !> so that end point was not the optimum. The leader is refitted from there: its figures
   !> (estimates, BIC, shares) and its intervals then belong to the lowest point its profiles
   !> met. In each stage (the fit tests, every test fitted) no point below the figures' is
   !> left, the intervals hold the estimates and, with every test fitted, the joint 95 % region
   !> of the three drifts holds the injected ones (a single 95 % interval alone missed its
   !> drift, 1.7e-8 against [1.79e-8, 2.48e-8], at an end point lower than the one before);
   !> the refit from a lower point happens in one stage at least (where a profile meets none,
   !> there is nothing to refit from)
   subroutine test_leader_lower(error)
      type(error_type), allocatable, intent(out) :: error
      type(diagnose_result) :: res
      real(dp), parameter :: truth(3) = [8.3e-8_dp, 1.7e-8_dp, -1.7e-8_dp]
      logical :: moved(2)
      call diagnose_deck('data/independent-drift/diagnose.nml', res, error)
      if (allocated(error)) return
      call check(error, res%leading > 0 .and. named_effect(res) == effect_index('drift') .and. &
                 allocated(res%joint), 'drift not named, or no stage with every test fitted: '//res%verdict)
      if (allocated(error)) return
      call lowest(res, 'fit tests', .false., moved(1))
      if (allocated(error)) return
      call lowest(res%joint, 'every test fitted', .true., moved(2))
      if (allocated(error)) return
      call check(error, any(moved), 'no stage''s leader was refitted from a lower point of its profile')
   contains
      !> The leader of stage r with no point below its figures met by its last profile; moved:
      !> it was refitted from a lower point its profile met; each interval holds its estimate
      !> (and, where every test is fitted, the joint region the injected drifts)
      subroutine lowest(r, stage, all_tests, moved)
         type(diagnose_result), intent(in) :: r
         character(len=*), intent(in) :: stage
         logical, intent(in) :: all_tests
         logical, intent(out) :: moved
         real(dp) :: wide
         integer :: g
         wide = sqrt(chi2_quantile_95(3)/chi2_quantile_95(1))
         moved = .false.
         call check(error, r%leading > 0, stage//': no leader')
         if (allocated(error)) return
         associate (ld => r%effects(r%leading))
            write (*, '(4x,a)') stage//': objective '//real_str(ld%f_unprofiled, 'es12.5')//' -> '// &
               real_str(ld%f_after, 'es12.5')//', lowest its last profile met '//real_str(ld%f_profile_low, 'es12.5')
            moved = ld%f_unprofiled > ld%f_after
            call check(error, ld%f_profile_low >= ld%f_after, &
                       stage//': the figures are not from the lowest point the profile met')
            if (allocated(error)) return
            do g = 1, size(ld%p)
               ! (a held-out test's own drift is fitted to it alone, with no interval)
               if (.not. ld%p_lo(g) < ld%p_hi(g)) cycle
               write (*, '(4x,a)') 'd '//str(g)//' = '//real_str(ld%p(g), 'es10.3')//' ['// &
                  real_str(ld%p_lo(g), 'es10.3')//', '//real_str(ld%p_hi(g), 'es10.3')//']'
               call check(error, ld%p_lo(g) <= ld%p(g) .and. ld%p(g) <= ld%p_hi(g), &
                          stage//': an interval excludes its own estimate')
               if (allocated(error)) return
               if (all_tests) then
                  ! The intervals are 95 % each: each alone leaves its injected drift out in one
                  ! case of twenty, one of three in about one of seven. The three together lie in
                  ! their joint 95 % region, whose projection on each drift is its interval
                  ! widened by sqrt(chi2_3/chi2_1) (Scheffe)
                  call check(error, ld%p(g) - wide*(ld%p(g) - ld%p_lo(g)) <= truth(g) .and. &
                             truth(g) <= ld%p(g) + wide*(ld%p_hi(g) - ld%p(g)), &
                             stage//': the injected drift outside the joint 95 % region of the three')
               end if
               if (allocated(error)) return
            end do
         end associate
      end subroutine lowest
   end subroutine test_leader_lower

   !> A lag of 0.10 s (independent data, data/independent-lag) lowers the objective at the
   !> baseline from 3.79 to 1.17, yet its screening column, differenced over the constants'
   !> step (1 ms), showed the integrator's error along a 1 ms transient at each corner more
   !> than the lag: a predicted fall of 1.3e-4, against 3.06 for the shift, so among all nine
   !> effects the lag was not refitted and the shift was named. Differenced over a tenth of
   !> the lag's low end (screening_steps), it screens as the shift does.
   subroutine test_lag_screening(error)
      type(error_type), allocatable, intent(out) :: error
      type(diagnose_result) :: res
      real(dp) :: fall(2)
      integer :: i
      call diagnose_deck('data/independent-lag/diagnose.nml', res, error)
      if (allocated(error)) return
      fall = 0.0_dp
      do i = 1, size(res%effects)
         if (res%effects(i)%k == effect_index('lag')) fall(1) = res%effects(i)%pred_drop
         if (res%effects(i)%k == effect_index('shift')) fall(2) = res%effects(i)%pred_drop
      end do
      write (*, '(4x,a)') 'screening: predicted fall, lag '//real_str(fall(1), 'es10.3')// &
         ', shift '//real_str(fall(2), 'es10.3')
      call check(error, fall(1) >= 0.5_dp*fall(2) .and. fall(2) > 1.0_dp, &
                 'the lag screens at '//real_str(fall(1), 'es10.3')//' against the shift''s '// &
                 real_str(fall(2), 'es10.3'))
      if (allocated(error)) return
      call check(error, named_effect(res) == effect_index('lag') .or. &
                 index(res%verdict, 'lag explains it') > 0 .or. index(res%verdict, 'lag (BIC') > 0, res%verdict)
   end subroutine test_lag_screening

   !> The fit problem of cfg's tests on placeholder data (ones at each test's output times),
   !> whose simulations then make the data
   subroutine placeholder_problem(cfg, prob, exps, error)
      type(run_config), intent(in) :: cfg
      type(fit_problem), intent(out) :: prob
      type(experiment_type), allocatable, intent(out) :: exps(:)
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: e
      integer :: i
      allocate (exps(size(cfg%tests)))
      do i = 1, size(cfg%tests)
         exps(i)%t = output_times(cfg%tests(i)%hist, cfg%tests(i)%dt_out)
         exps(i)%y = spread(1.0_dp, 1, size(exps(i)%t))
      end do
      call setup_problem(cfg, prob, e, exps)
      call check(error, .not. allocated(e), 'setup failed')
   end subroutine placeholder_problem

   !> The diagnosis of the deck at path, with its own options, into res
   !> The second back stress named, its rate fitted (not held) and its 95 % interval holding
   !> the injected rate gamma3
   subroutine check_gamma3(res, gamma3, error)
      type(diagnose_result), intent(in) :: res
      real(dp), intent(in) :: gamma3
      type(error_type), allocatable, intent(out) :: error
      integer :: k
      call check(error, named_effect(res) == effect_index('backstress2'), res%verdict)
      if (allocated(error)) return
      k = findloc(res%effects%k, effect_index('backstress2'), dim=1)
      associate (e => res%effects(k))
         call check(error, .not. e%held .and. size(e%p) == 2, 'gamma3 held or not fitted')
         if (allocated(error)) return
         write (*, '(4x,a,3es11.3)') 'gamma3 and its interval:', e%p(2), e%p_lo(2), e%p_hi(2)
         call check(error, e%p_lo(2) <= gamma3 .and. gamma3 <= e%p_hi(2), 'the interval of gamma3 '// &
                    'does not hold the injected '//real_str(gamma3, 'f0.0'))
      end associate
   end subroutine check_gamma3

   subroutine diagnose_deck(path, res, error)
      character(len=*), intent(in) :: path
      type(diagnose_result), intent(out) :: res
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: e
      type(run_config) :: cfg
      type(diagnose_options) :: opts
      call read_config(path, cfg, e)
      if (.not. allocated(e)) call diagnose_options_of(cfg, opts, e)
      if (.not. allocated(e)) call diagnose_run(cfg, opts, res, e)
      if (allocated(e)) call test_failed(error, 'diagnosis failed: '//e%message)
   end subroutine diagnose_deck

   subroutine decay_residuals(self, xs, rs, fs, ok, error)
      class(decay_problem), intent(inout) :: self
      real(dp), intent(in) :: xs(:, :)
      real(dp), intent(out) :: rs(:, :)
      real(dp), intent(out) :: fs(:)
      logical, intent(out) :: ok(:)
      type(uerror), allocatable, intent(out) :: error
      integer :: k
      do k = 1, size(xs, 2)
         rs(:, k) = self%y - xs(1, k)*exp(-xs(2, k)*self%t)
         fs(k) = sum(rs(:, k)**2)
         ok(k) = xs(2, k) <= self%fail_above
         if (.not. ok(k)) fs(k) = failed_objective
      end do
   end subroutine decay_residuals

   pure integer function decay_nres(self) result(m)
      class(decay_problem), intent(in) :: self
      m = size(self%t)
   end function decay_nres

   subroutine decay_eval(self, x, f, error)
      class(decay_problem), intent(inout) :: self
      real(dp), intent(in) :: x(:)
      real(dp), intent(out) :: f
      type(uerror), allocatable, intent(out) :: error
      f = sum((self%y - x(1)*exp(-x(2)*self%t))**2)
      if (x(2) > self%fail_above) f = failed_objective
   end subroutine decay_eval
end module test_diagnose_data
