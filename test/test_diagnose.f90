!> Tests of the diagnosis: the extended model is the plain one at zero effect, the effects
!> do what their documentation says, the statistics behave on known inputs, bad inputs are
!> clear errors, and a small self-check finds injected effects and no false alarm
module test_diagnose
   use testdrive, only: error_type, unittest_type, new_unittest, check, test_failed
   use usharp_kinds, only: dp
   use usharp_math, only: cubic_piece
   use usharp_error, only: uerror => error_type
   use usharp_config, only: run_config
   use usharp_input, only: read_config
   use usharp_history, only: history_type, cyclic_history, output_times, control_stress
   use usharp_model_miller, only: miller_model, model_setup
   use usharp_simulation, only: sim_result, solver_options
   use usharp_cvode_driver, only: simulate_cvode
   use usharp_rosenbrock_driver, only: simulate_rosenbrock
   use usharp_effects, only: test_effects, lagged_value, lag_corners, effect_model, extended_rates, n_extended, &
                             effect_catalogue, effect_index, effect_info, n_effects, effect_acts
   use usharp_regions, only: runs_z, noise_sd, gap_se, noise_var_rse, point_classes, region_stat, region_of, &
                             class_loading, class_unloading, class_reversal, class_hold
   use, intrinsic :: ieee_arithmetic, only: ieee_value, ieee_quiet_nan, ieee_positive_inf
   use usharp_strings, only: real_str, interval_end, interval_format, str
   use usharp_diagnose, only: diagnose_options, diagnose_result, diagnose_run, &
                              diagnose_options_of, gn_decrease, diagnose_baseline, diagnose_context, &
                             n_leading, simpler_rivals
   use usharp_selfcheck, only: selfcheck_result, selfcheck_run
   use usharp_distributions, only: gamma_q, chi2_sf, chi2_isf, ncx2_sf
   use usharp_diagnose_types, only: effect_outcome, joint_wanted, named_effect, joint_decides, fit_gap_left, rest_wanted, &
                                    baseline_left_behind, separating_d, open_spread, &
                                    held_fit_only, form_beats_leader, joint_reason, joint_held_only, joint_form_open, &
                                    joint_not_carried, rate_open, rate_at_end, &
                                    joint_bic_only, joint_partial, joint_loose, joint_held_fit, joint_form_beats, gap_fit_ref
   use usharp_diagnose_verdict, only: conclude, joint_verdict, verdict_of, alike_note, bound_note, missed_note
   use usharp_diagnose_refit, only: judge, rate_undetermined, rate_doubt, with_params, other_sign, global_baseline_starts, &
                                    rate_rungs, shown_groups
   use usharp_diagnose_screen, only: basin_points
   use usharp_diagnose_separate, only: separate
   use usharp_rng, only: rng_type
   use usharp_diagnose_numerics, only: best_of_starts, global_points, lm_ftol, lm_itermax, held_rate, ratio_beyond_doubt, &
                                       at_box_end, at_bound, beyond_limit, limit_measures, judge_held_values, &
                                       backstress2_starts, below_resolved, resolved_share, low_end_deltas, &
                                       low_end_starts, distinct_starts
   use usharp_diagnose_units, only: lm_unit, starts_unit
   use usharp_diagnose_memo, only: run_memo
   use usharp_diagnose_journal, only: diagnose_journal
   use usharp_effect_problem, only: effect_problem, new_effect_problem, simulate_effect
   use usharp_diagnose_profile, only: open_beyond_estimate
   use usharp_diagnose_memo, only: effect_reals
   use usharp_effect_values, only: test_effects
   use usharp_objective, only: fit_problem, setup_problem
   use usharp_optimiser, only: optimum_type
   use usharp_diagnose_specimen, only: specimen_result, specimen_deviance, constants_directions, &
                                       specimen_noncentrality, profiled_deviance
   use usharp_lapack, only: solve_dense, logdet_spd
   use omp_lib, only: omp_set_num_threads, omp_get_max_threads
   use test_util, only: write_text, check_message, scratch_dir
   implicit none
   private
   public :: collect_diagnose, model_groups, small_matrix

   character(len=*), parameter :: model_groups(3) = [character(len=100) :: &
      "&model temperature = 866.15, tm = 1800.0, youngs = 22.5e3, poisson = 0.3 /", &
      "&constants a1 = 0.8, a2 = 7.42e-5, b = 1.0e15, c2 = 0.1, h1 = 280.0, h2 = 100.0,", &
      "  n = 5.8, q = 91000.0 /"]

   !> A small matrix for the self-check test: two fit tests and one held out
   character(len=*), parameter :: small_matrix(9) = [character(len=100) :: &
      "&fit fitted = 'A1', 'A2', 'B', 'C2', 'H1', 'H2', 'n', method = 'lm' /", &
      "&test name = 'cyc1', history = 'cyclic', dt_out = 0.5, strain_range = 0.01,", &
      "  strain_rate = 1.0e-3, cycles = 6 /", &
      "&test name = 'cyc2-hold', history = 'cyclic', dt_out = 0.5, strain_range = 0.02,", &
      "  strain_rate = 1.0e-3, cycles = 2, hold_max = 200.0 /", &
      "&test name = 'held', history = 'cyclic', dt_out = 1.0, strain_range = 0.015,", &
      "  strain_rate = 1.0e-4, cycles = 1 /", &
      "&diagnose holdout = 'held', effects = 'compliance', 'lag', 'shift', n_refit = 2,", &
      "  reps = 1, seed = 3, noise = 0.01 /"]

contains

   subroutine collect_diagnose(testsuite)
      type(unittest_type), allocatable, intent(out) :: testsuite(:)
      testsuite = [ &
         new_unittest('extended-model-at-zero-is-the-plain-model', test_zero_effect), &
         new_unittest('extended-rodas4-vs-tight-reference', test_extended_rodas4), &
         new_unittest('compliance-is-a-softer-machine', test_compliance), &
         new_unittest('gain-reads-the-stress-through-its-factor', test_gain), &
         new_unittest('lag-solution-against-differences', test_lag), &
         new_unittest('runs-test-on-known-sequences', test_runs), &
         new_unittest('noise-estimate-from-second-differences', test_noise), &
         new_unittest('gap-standard-error-against-monte-carlo', test_gap_se), &
         new_unittest('score-test-on-a-linear-model', test_score), &
         new_unittest('history-classes-and-cycles', test_classes), &
         new_unittest('diagnose-bad-inputs', test_bad_inputs), &
         new_unittest('effects-that-do-not-act-on-the-model-left-out', test_inert_effects), &
         new_unittest('global-baseline-starts-from-the-refits-constants', test_global_baseline_starts), &
         new_unittest('baseline-ignores-held-out-data', test_held_out_unused), &
         new_unittest('baseline-fitted-from-an-unconverged-start', test_unconverged_start), &
         new_unittest('starts-on-threads-as-one-after-the-other', test_starts_threads), &
         new_unittest('runs-made-before-are-not-made-again', test_memo), &
         new_unittest('resume-refuses-a-unit-made-for-another-request', test_unit_request), &
         new_unittest('verdict-simpler-effect-without-strong-evidence', test_parsimony), &
         new_unittest('verdict-names-the-leaders-size-and-where-it-acts', test_verdict_size), &
         new_unittest('verdict-of-no-effect-names-weak-evidence', test_weak_evidence), &
         new_unittest('screening-near-ties-are-refitted', test_near_ties), &
         new_unittest('simpler-rivals-of-a-per-test-leader', test_simpler_rivals), &
         new_unittest('effect-below-what-is-resolved', test_below_resolved), &
         new_unittest('confirmed-below-the-floors', test_below_floors), &
         new_unittest('sub-sample-delay-confirmed-when-measured', test_measured_delay), &
         new_unittest('prediction-of-loose-constants-confirms-nothing', test_loose_prediction), &
         new_unittest('baseline-left-behind-by-a-refits-constants', test_left_behind), &
         new_unittest('bic-in-each-tests-own-variance', test_bic_per_test), &
         new_unittest('per-test-effect-counted-on-the-tests-that-show-it', test_bic_shown), &
         new_unittest('when-every-test-is-fitted-together', test_joint_rule), &
         new_unittest('partial-prediction-fitted-with-every-test', test_partial_carry), &
         new_unittest('held-out-agreement-at-constants-the-fit-tests-allow', test_held_agreement), &
         new_unittest('specimen-residual-covariance-with-the-constants', test_specimen_quad), &
         new_unittest('lower-ranked-refits-when-the-leader-leaves-a-gap', test_gap_left_rule), &
         new_unittest('leader-fitted-to-the-held-out-tests-gives-way', test_held_fit_rule), &
         new_unittest('form-left-open-below-the-floor-fits-every-test', test_open_below_floor), &
         new_unittest('magnitude-beyond-its-limit-beyond-doubt', test_beyond_doubt), &
         new_unittest('rate-held-where-undetermined', test_rate_held), &
         new_unittest('refit-starts-in-both-signs-basins', test_both_signs), &
         new_unittest('refit-starts-in-each-rates-basin', test_rate_rungs), &
         new_unittest('held-out-prediction-open-between-end-points', test_alike_note), &
         new_unittest('parameters-at-the-end-of-their-box-flagged', test_box_end), &
         new_unittest('second-back-stress-box-holds-the-peak-saturation', test_backstress2_box), &
         new_unittest('one-test-effect-starts-at-zero-and-its-low-ends', test_low_end_starts), &
         new_unittest('a-test-that-sees-the-same-point-is-not-simulated-again', test_rows_reused), &
         new_unittest('one-plausibility-rule-for-both-diagnoses', test_beyond_limit), &
         new_unittest('interval-that-leaves-out-its-estimate-opens', test_open_beyond_estimate), &
         new_unittest('gap-shares-of-the-lower-baseline', test_gap_fit_ref), &
         new_unittest('verdict-says-the-refit-ran-to-a-bound', test_bound_note), &
         new_unittest('held-out-values-judged-against-their-limits', test_held_values), &
         new_unittest('run-key-holds-every-effect-value', test_effect_reals), &
         new_unittest('chi-square-tails-against-references', test_chi2_tails), &
         new_unittest('numbers-print-with-a-leading-zero', test_number_format), &
         new_unittest('separating-test-for-effects-alike', test_separate), &
         new_unittest('softening-saturates-jacobian-against-differences', test_softening), &
         new_unittest('separating-test-softening-against-initial', test_separate_softening), &
         new_unittest('selfcheck-finds-injected-effects', test_selfcheck), &
         new_unittest('selfcheck-at-a-start-names-the-matrix-and-effect', test_selfcheck_start), &
         new_unittest('could-miss-said-within-the-limits', test_missed_note)]
   end subroutine collect_diagnose

   !> A thesis model, set up
   subroutine thesis_model(model)
      type(miller_model), intent(out) :: model
      type(uerror), allocatable :: e
      call model_setup(model, e)
   end subroutine thesis_model

   subroutine cycles(hist, e)
      type(history_type), intent(out) :: hist
      type(uerror), allocatable, intent(out) :: e
      call cyclic_history(0.01_dp, 0.0_dp, 1.0e-3_dp, 0.0_dp, 3, 60.0_dp, 0.0_dp, hist, e)
   end subroutine cycles

   !> With every effect zero the extended (5-state, difference-quotient Jacobian) model gives
   !> the plain model's stress to the integration tolerance
   subroutine test_zero_effect(error)
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: e
      type(miller_model) :: model
      type(history_type) :: hist
      type(solver_options) :: opts
      type(sim_result) :: a, b
      type(test_effects) :: none
      call thesis_model(model)
      call cycles(hist, e)
      opts%rtol = 1.0e-10_dp
      opts%atol_strain = 1.0e-14_dp
      call simulate_cvode(model, hist, output_times(hist, 1.0_dp), opts, a, e)
      if (.not. allocated(e)) call simulate_cvode(model, hist, output_times(hist, 1.0_dp), opts, b, e, none)
      call check(error, .not. allocated(e), 'simulation failed')
      if (allocated(error)) return
      call check(error, maxval(abs(a%stress - b%stress)) < 1.0e-6_dp*maxval(abs(a%stress)), &
                 'extended model at zero differs from the plain one')
   end subroutine test_zero_effect

   !> RODAS4 on the extended model with every effect of the simulation on (compliance, lag,
   !> initial state, specimen factors, softening, second back stress), three cycles with a
   !> one-minute hold: at its default tolerances within 1e-4 of the peak of CVODE at rtol
   !> 1e-10, at rtol 1e-9 within 1e-6 (it converges to the same solution)
   subroutine test_extended_rodas4(error)
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: e
      type(miller_model) :: model
      type(history_type) :: hist
      type(solver_options) :: tight, def, fine
      type(sim_result) :: ref, a, b
      type(test_effects) :: eff
      real(dp) :: peak, dev_def, dev_fine
      character(len=100) :: buf
      call thesis_model(model)
      call cyclic_history(0.01_dp, 0.0_dp, 1.0e-3_dp, 0.0_dp, 3, 60.0_dp, 0.0_dp, hist, e)
      eff%compliance = 0.05_dp
      eff%lag = 0.2_dp
      eff%r0 = 1.0_dp
      eff%dd0 = -0.5_dp
      eff%strength = 0.04_dp
      eff%soften = 0.1_dp
      eff%soften_rate = 50.0_dp
      eff%h3 = 1500.0_dp
      eff%gamma3 = 300.0_dp
      tight%integrator = 'cvode'
      tight%rtol = 1.0e-10_dp
      tight%atol_strain = 1.0e-14_dp
      fine%rtol = 1.0e-9_dp
      fine%atol_strain = 1.0e-13_dp
      call simulate_cvode(model, hist, output_times(hist, 0.5_dp), tight, ref, e, eff)
      if (.not. allocated(e)) call simulate_rosenbrock(model, hist, output_times(hist, 0.5_dp), &
                                                       def, a, e, eff)
      if (.not. allocated(e)) call simulate_rosenbrock(model, hist, output_times(hist, 0.5_dp), &
                                                       fine, b, e, eff)
      call check(error, .not. allocated(e), 'simulation failed')
      if (allocated(error)) return
      peak = maxval(abs(ref%stress))
      dev_def = maxval(abs(a%stress - ref%stress))/peak
      dev_fine = maxval(abs(b%stress - ref%stress))/peak
      write (buf, '(a,2es10.2)') 'RODAS4 default, rtol 1e-9: max |dsig|/peak ', dev_def, dev_fine
      call check(error, dev_def <= 1.0e-4_dp .and. dev_fine <= 1.0e-6_dp .and. dev_fine < dev_def, trim(buf))
   end subroutine test_extended_rodas4

   !> Under strain control a compliance kappa acts as the modulus E/(1 + kappa)
   subroutine test_compliance(error)
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: e
      type(miller_model) :: model, soft
      type(history_type) :: hist
      type(solver_options) :: opts
      type(sim_result) :: a, b
      type(test_effects) :: eff, none
      call thesis_model(model)
      call cycles(hist, e)
      opts%rtol = 1.0e-10_dp
      opts%atol_strain = 1.0e-14_dp
      eff%compliance = 0.1_dp
      soft = model
      soft%youngs = model%youngs/1.1_dp
      call simulate_cvode(model, hist, output_times(hist, 1.0_dp), opts, a, e, eff)
      if (.not. allocated(e)) call simulate_cvode(soft, hist, output_times(hist, 1.0_dp), opts, b, e, none)
      call check(error, .not. allocated(e), 'simulation failed')
      if (allocated(error)) return
      call check(error, maxval(abs(a%stress - b%stress)) < 1.0e-6_dp*maxval(abs(a%stress)), &
                 'compliance is not the softer modulus')
      if (allocated(error)) return
      ! and it changes the answer by far more than that
      call simulate_cvode(model, hist, output_times(hist, 1.0_dp), opts, b, e, none)
      call check(error, maxval(abs(a%stress - b%stress)) > 1.0e-2_dp*maxval(abs(a%stress)), &
                 'compliance has no effect')
   end subroutine test_compliance

   !> A stress channel of gain g: under strain control the measured stress is (1 + g) times
   !> the plain model's; under stress control the specimen sees the command over (1 + g), so
   !> the strain is the plain model's under that command (a creep test at 15 and at
   !> 15/1.04 ksi), and the reading is the command again
   subroutine test_gain(error)
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: e
      type(miller_model) :: model
      type(history_type) :: hist, creep, lower
      type(solver_options) :: opts
      type(sim_result) :: a, b
      type(test_effects) :: eff, none
      real(dp), allocatable :: t(:)
      call thesis_model(model)
      call cycles(hist, e)
      eff%gain = 0.04_dp
      t = output_times(hist, 1.0_dp)
      call simulate_effect(model, eff, hist, t, opts, a, e)
      if (.not. allocated(e)) call simulate_effect(model, none, hist, t, opts, b, e)
      call check(error, .not. allocated(e), 'simulation failed')
      if (allocated(error)) return
      call check(error, maxval(abs(a%stress - 1.04_dp*b%stress)) < 1.0e-12_dp*maxval(abs(b%stress)) .and. &
                 maxval(abs(a%strain - b%strain)) == 0.0_dp, 'strain control: the stress is not read through the gain')
      if (allocated(error)) return
      creep%control = control_stress
      creep%t = [0.0_dp, 1.0_dp, 601.0_dp]
      creep%v = [0.0_dp, 15.0_dp, 15.0_dp]
      lower = creep
      lower%v = (1.0_dp/(1.0_dp + eff%gain))*creep%v
      t = output_times(creep, 1.0_dp)
      call simulate_effect(model, eff, creep, t, opts, a, e)
      if (.not. allocated(e)) call simulate_effect(model, none, lower, t, opts, b, e)
      call check(error, .not. allocated(e), 'simulation failed')
      if (allocated(error)) return
      call check(error, maxval(abs(a%strain - b%strain)) < 1.0e-12_dp*maxval(abs(b%strain)), &
                 'stress control: the specimen does not see the command over 1 + g')
      if (allocated(error)) return
      call check(error, maxval(abs(a%stress - 1.04_dp*b%stress)) < 1.0e-12_dp*15.0_dp, &
                 'stress control: the reading is not the command')
      if (allocated(error)) return
      ! and the gain moves the creep strain far beyond that
      call simulate_effect(model, none, creep, t, opts, b, e)
      call check(error, maxval(abs(a%strain - b%strain)) > 1.0e-2_dp*maxval(abs(b%strain)), &
                 'stress control: the gain has no effect')
   end subroutine test_gain

   !> The closed-form lag solves dy/dt = (u - y)/tau, of a piecewise-linear control and of a
   !> cubic spline's pieces (a smooth forcing): its rate against central differences of its
   !> value, and the ODE residual; a vanishing tau returns the command
   subroutine test_lag(error)
      type(error_type), allocatable, intent(out) :: error
      real(dp), parameter :: tc(3) = [0.0_dp, 10.0_dp, 30.0_dp], vc(3) = [0.0_dp, 0.01_dp, -0.01_dp]
      ! second derivatives of a spline through the same corners (not a natural one: any
      ! moments make a twice-differentiable cubic on each piece)
      real(dp), parameter :: mc(3) = [2.0e-4_dp, -5.0e-4_dp, 3.0e-4_dp]
      real(dp), parameter :: tau = 0.7_dp, h = 1.0e-5_dp
      real(dp) :: yk(3), y, yd, yp, ym, dum, t, u
      integer :: k, pass
      do pass = 1, 2
         if (pass == 1) then
            yk = lag_corners(tc, vc, tau)
         else
            yk = lag_corners(tc, vc, tau, mc)
         end if
         do k = 1, 2
            t = tc(k) + 0.37_dp*(tc(k + 1) - tc(k))
            if (pass == 1) then
               call lagged_value(tc, vc, yk, k, tau, t, y, yd)
               call lagged_value(tc, vc, yk, k, tau, t + h, yp, dum)
               call lagged_value(tc, vc, yk, k, tau, t - h, ym, dum)
               u = vc(k) + (vc(k + 1) - vc(k))*(t - tc(k))/(tc(k + 1) - tc(k))
            else
               call lagged_value(tc, vc, yk, k, tau, t, y, yd, mc)
               call lagged_value(tc, vc, yk, k, tau, t + h, yp, dum, mc)
               call lagged_value(tc, vc, yk, k, tau, t - h, ym, dum, mc)
               call cubic_piece(tc, vc, mc, k, t, u, dum)
            end if
            call check(error, abs(yd - (yp - ym)/(2.0_dp*h)) < 1.0e-7_dp*abs(yd) + 1.0e-12_dp, &
                       'lag rate differs from differences')
            if (allocated(error)) return
            call check(error, abs(yd - (u - y)/tau) < 1.0e-10_dp, 'lag does not solve its ODE')
            if (allocated(error)) return
         end do
         ! the lagged value runs on continuously across corner 2
         if (pass == 2) then
            call lagged_value(tc, vc, yk, 1, tau, tc(2), yp, dum, mc)
            call lagged_value(tc, vc, yk, 2, tau, tc(2), ym, dum, mc)
            call check(error, abs(yp - ym) < 1.0e-15_dp .and. abs(yk(2) - yp) < 1.0e-15_dp, &
                       'the lag of the spline jumps at a corner')
            if (allocated(error)) return
         end if
      end do
      call lagged_value(tc, vc, yk, 2, 1.0e-9_dp, 20.0_dp, y, yd)
      call check(error, abs(y) < 1.0e-8_dp, 'a vanishing lag does not return the command')
      if (allocated(error)) return
      call cubic_piece(tc, vc, mc, 2, 20.0_dp, u, dum)
      call lagged_value(tc, vc, lag_corners(tc, vc, 1.0e-9_dp, mc), 2, 1.0e-9_dp, 20.0_dp, y, yd, mc)
      call check(error, abs(y - u) < 1.0e-8_dp*abs(vc(2)), 'a vanishing lag does not return the spline')
   end subroutine test_lag

   subroutine test_runs(error)
      type(error_type), allocatable, intent(out) :: error
      real(dp) :: e(400)
      type(rng_type) :: rng
      integer :: i
      e = [(merge(1.0_dp, -1.0_dp, mod(i, 2) == 0), i=1, 400)]
      call check(error, runs_z(e) > 10.0_dp, 'alternating signs: too many runs not seen')
      if (allocated(error)) return
      e = [(merge(1.0_dp, -1.0_dp, mod(i/50, 2) == 0), i=1, 400)]
      call check(error, runs_z(e) < -10.0_dp, 'blocks: too few runs not seen')
      if (allocated(error)) return
      call rng%seed(5)
      do i = 1, 400
         e(i) = rng%normal()
      end do
      call check(error, abs(runs_z(e)) < 3.0_dp, 'white noise flagged')
      if (allocated(error)) return
      ! One sign throughout (a bias, however smooth) is not noise: one run of 209
      call check(error, abs(runs_z(abs(e(1:209)) + 1.0_dp) + sqrt(208.0_dp)) < 1.0e-12_dp, &
                 'a residual of one sign: z '//real_str(runs_z(abs(e(1:209)) + 1.0_dp), 'f0.2'))
      if (allocated(error)) return
      ! Nearly one sign: the counts alone leave the Wald-Wolfowitz test no room
      e(1:209) = abs(e(1:209)) + 1.0_dp
      e(100) = -1.0_dp
      call check(error, runs_z(e(1:209)) < -10.0_dp, 'one negative in 209: not seen')
      if (allocated(error)) return
      ! Five points with 283 times the noise's mean square are structured, though no runs
      ! test of 5 points reaches z = -3; five with 2 times are not
      block
         type(region_stat) :: st
         real(dp) :: r5(5)
         r5 = [1.0_dp, -1.0_dp, 1.0_dp, -1.0_dp, 1.0_dp]*sqrt(283.0_dp)
         st = region_of('t', 'elastic', spread(.true., 1, 5), r5, r5, spread(1.0_dp, 1, 5))
         call check(error, st%structured .and. abs(st%ratio - 283.0_dp) < 1.0e-9_dp, &
                    'a short region far above its noise called noise')
         if (allocated(error)) return
         st = region_of('t', 'elastic', spread(.true., 1, 5), r5/sqrt(141.5_dp), r5, spread(1.0_dp, 1, 5))
         call check(error, .not. st%structured, 'a short region at twice its noise called structured')
      end block
   end subroutine test_runs

   !> A smooth signal sampled densely plus white noise of sd 0.1: the estimate within 5 %
   subroutine test_noise(error)
      type(error_type), allocatable, intent(out) :: error
      real(dp) :: y(20000), sd, e
      type(rng_type) :: rng
      integer :: i
      call rng%seed(7)
      do i = 1, size(y)
         y(i) = 40.0_dp*sin(real(i, dp)*1.0e-3_dp) + 0.1_dp*rng%normal()
      end do
      sd = noise_sd(y)
      call check(error, abs(sd/0.1_dp - 1.0_dp) < 0.05_dp, 'noise estimate off')
      if (allocated(error)) return
      ! Independent noise gives the same sd from second differences 5 samples apart (the
      ! correlation test of the diagnosis); AR(1) noise of correlation 0.9 (sd 0.1) gives
      ! sqrt((6 - 8 rho**5 + 2 rho**10)/(6 - 8 rho + 2 rho**2)) = 2.17 times that from neighbours,
      ! above the 2 at which the diagnosis calls it correlated
      call check(error, abs(noise_sd(y, 5)/sd - 1.0_dp) < 0.05_dp, 'independent noise: lag 5 against 1 '// &
                 real_str(noise_sd(y, 5)/sd, 'f0.3'))
      if (allocated(error)) return
      e = 0.0_dp
      do i = 1, size(y)
         e = 0.9_dp*e + sqrt(1.0_dp - 0.81_dp)*0.1_dp*rng%normal()
         y(i) = 40.0_dp*sin(real(i, dp)*1.0e-3_dp) + e
      end do
      call check(error, abs(noise_sd(y, 5)/noise_sd(y) - 2.17_dp) < 0.1_dp, 'AR(1) noise of 0.9: lag 5 '// &
                 'against 1 '//real_str(noise_sd(y, 5)/noise_sd(y), 'f0.3')//', not 2.17')
      if (allocated(error)) return
      call check(error, abs(noise_sd(y)/0.1_dp - sqrt(0.42_dp/6.0_dp)) < 0.03_dp, 'AR(1) noise of 0.9 reads '// &
                 'as sqrt(0.42/6) of its sd from neighbours: '//real_str(noise_sd(y)/0.1_dp, 'f0.3'))
   end subroutine test_noise

   !> The scatter of the noise estimate and of the structured gap a pure-noise residual
   !> leaves, over 2000 draws of a 600-point test with uneven weights, against noise_var_rse
   !> and gap_se within 10 % (the Monte Carlo's own error is 1.6 %)
   subroutine test_gap_se(error)
      type(error_type), allocatable, intent(out) :: error
      integer, parameter :: n = 600, draws = 2000
      real(dp) :: y(n), e(n), w(n), v(draws), g(draws), sd, se
      type(rng_type) :: rng
      integer :: i, k
      call rng%seed(11)
      w = [(1.0_dp + 0.5_dp*sin(0.05_dp*i), i=1, n)]
      do k = 1, draws
         do i = 1, n
            e(i) = 0.1_dp*rng%normal()
         end do
         y = 40.0_dp*sin(0.02_dp*[(real(i, dp), i=1, n)]) + e
         sd = noise_sd(y)
         v(k) = (sd/0.1_dp)**2
         g(k) = sum((w*e)**2) - sum((w*sd)**2)
      end do
      se = sqrt(sum((v - sum(v)/draws)**2)/(draws - 1))*sqrt(real(n, dp))
      call check(error, abs(se/noise_var_rse - 1.0_dp) < 0.1_dp, 'noise estimate scatters by '// &
                 'sqrt(n) x '//real_str(se, 'f0.3')//', not '//real_str(noise_var_rse, 'f0.3'))
      if (allocated(error)) return
      se = gap_se((0.1_dp*w)**2, spread(1, 1, n), [n], [.true.])
      sd = sqrt(sum((g - sum(g)/draws)**2)/(draws - 1))
      call check(error, abs(sd/se - 1.0_dp) < 0.1_dp, 'gap scatters by '//real_str(sd, 'es10.3')// &
                 ', gap_se gives '//real_str(se, 'es10.3'))
   end subroutine test_gap_se

   !> For residuals r = J a + n with n orthogonal to J, the Gauss-Newton fall is |J a|**2 and
   !> the step is -a, also with badly scaled columns
   subroutine test_score(error)
      type(error_type), allocatable, intent(out) :: error
      real(dp) :: jac(50, 3), r(50), a(3), step(3), drop, nvec(50)
      type(rng_type) :: rng
      integer :: i, j
      call rng%seed(11)
      do j = 1, 3
         do i = 1, 50
            jac(i, j) = rng%normal()*10.0_dp**(2*j)
         end do
      end do
      a = [0.3_dp, -0.002_dp, 1.0e-5_dp]
      do i = 1, 50
         nvec(i) = rng%normal()
      end do
      ! Remove from the noise its part in the span of J (normal equations, small system)
      call gn_decrease(jac, nvec, drop, step)
      nvec = nvec + matmul(jac, step)
      r = matmul(jac, a) + nvec
      call gn_decrease(jac, r, drop, step)
      call check(error, abs(drop/sum(matmul(jac, a)**2) - 1.0_dp) < 1.0e-8_dp, 'fall wrong')
      if (allocated(error)) return
      call check(error, maxval(abs(step + a)/abs(a)) < 1.0e-6_dp, 'step wrong')
   end subroutine test_score

   !> 1 % cycles with a hold at the peak: hold, loading, unloading and reversal points where
   !> the history says, and the cycle count
   subroutine test_classes(error)
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: e
      type(history_type) :: hist
      real(dp), allocatable :: t(:)
      integer, allocatable :: cls(:), cyc(:)
      call cycles(hist, e)
      ! Quarter cycle: 5 s to +0.5 %, hold 60 s, 10 s to -0.5 %, 10 s back...
      t = [2.0_dp, 30.0_dp, 65.5_dp, 68.0_dp, 72.0_dp, 76.0_dp, hist%end_time() - 1.0_dp]
      allocate (cls(size(t)), cyc(size(t)))
      call point_classes(hist, t, cls, cyc)
      call check(error, cls(1) == class_loading .and. cls(2) == class_hold .and. &
                 cls(3) == class_reversal .and. cls(5) == class_loading .and. cls(4) == class_unloading, &
                 'classes wrong')
      if (allocated(error)) return
      call check(error, cyc(1) == 1 .and. cyc(7) == 3, 'cycle count wrong')
   end subroutine test_classes

   subroutine test_bad_inputs(error)
      use usharp_cmd_diagnose, only: diagnose_command
      use usharp_filesys, only: file_exists
      use usharp_strings, only: report_line_len
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: e
      character(len=report_line_len), allocatable :: lines(:)
      type(run_config) :: cfg
      type(diagnose_options) :: opts
      type(diagnose_result) :: res
      character(len=100), parameter :: tests(2) = [character(len=100) :: &
         "&test name = 'a', history = 'relaxation', data_file = 'a.txt' /", &
         "&test name = 'b', history = 'relaxation', data_file = 'a.txt' /"]
      call read_config(write_text('diag-effect.nml', [character(len=100) :: model_groups, &
         "&fit fitted = 'B' /", "&diagnose effects = 'creep-fatigue' /", tests]), cfg, e)
      if (.not. allocated(e)) call diagnose_options_of(cfg, opts, e)
      call check_message(error, e, "&diagnose: effects: no effect is named 'creep-fatigue'")
      if (allocated(error)) return
      call read_config(write_text('diag-starts.nml', [character(len=100) :: model_groups, &
         "&fit fitted = 'B' /", "&diagnose refit_starts = 0 /", tests]), cfg, e)
      call check_message(error, e, '&diagnose: refit_starts must be >= 1')
      if (allocated(error)) return
      call read_config(write_text('diag-global.nml', [character(len=100) :: model_groups, &
         "&fit fitted = 'B' /", "&diagnose global_starts = -1 /", tests]), cfg, e)
      call check_message(error, e, '&diagnose: global_starts must be >= 0')
      if (allocated(error)) return
      call read_config(write_text('diag-rows.nml', [character(len=100) :: model_groups, &
         "&fit fitted = 'B' /", "&diagnose rows = 'none', 'creep' /", tests]), cfg, e)
      if (.not. allocated(e)) call diagnose_options_of(cfg, opts, e)
      call check_message(error, e, "&diagnose: rows: no effect is named 'creep'")
      if (allocated(error)) return
      ! An effect named twice, a row the effects do not list, a noise in percent, a slope of
      ! ln E no metal has
      call read_config(write_text('diag-twice.nml', [character(len=100) :: model_groups, &
         "&fit fitted = 'B' /", "&diagnose effects = 'softening', 'lag', 'Softening' /", tests]), cfg, e)
      call check_message(error, e, "&diagnose: effects names 'Softening' twice")
      if (allocated(error)) return
      call read_config(write_text('diag-rowlist.nml', [character(len=100) :: model_groups, &
         "&fit fitted = 'B' /", "&diagnose effects = 'drift', rows = 'lag' /", tests]), cfg, e)
      if (.not. allocated(e)) call diagnose_options_of(cfg, opts, e)
      call check_message(error, e, "&diagnose: rows: 'lag' is injected but effects does not list it")
      if (allocated(error)) return
      call read_config(write_text('diag-noise.nml', [character(len=100) :: model_groups, &
         "&fit fitted = 'B' /", "&diagnose noise = 5.0 /", tests]), cfg, e)
      call check_message(error, e, "&diagnose: noise = 5.000 is a share of the peak stress")
      if (allocated(error)) return
      call read_config(write_text('diag-dlne.nml', [character(len=100) :: model_groups, &
         "&fit fitted = 'B' /", "&diagnose dlnE_dT = 1e30 /", tests]), cfg, e)
      call check_message(error, e, "&diagnose: dlnE_dT = 1.000E+30 1/K is no metal's")
      if (allocated(error)) return
      call read_config(write_text('diag-holdout.nml', [character(len=100) :: model_groups, &
         "&fit fitted = 'B' /", "&diagnose holdout = 'c' /", tests]), cfg, e)
      if (.not. allocated(e)) call diagnose_options_of(cfg, opts, e)
      call check_message(error, e, "&diagnose: holdout: no &test is named 'c'")
      if (allocated(error)) return
      call write_relaxation_data('a.txt', 1.0_dp, e)
      call check(error, .not. allocated(e), 'relaxation data not written')
      if (allocated(error)) return
      ! No &diagnose at all: the group is named, not its variable
      call read_config(write_text('diag-none.nml', [character(len=100) :: model_groups, &
         "&fit fitted = 'B' /", tests]), cfg, e)
      if (.not. allocated(e)) call diagnose_options_of(cfg, opts, e)
      if (.not. allocated(e)) call diagnose_run(cfg, opts, res, e)
      call check_message(error, e, 'group &diagnose is missing')
      if (allocated(error)) return
      call read_config(write_text('diag-empty.nml', [character(len=100) :: model_groups, &
         "&fit fitted = 'B' /", "&diagnose n_refit = 3 /", tests]), cfg, e)
      if (.not. allocated(e)) call diagnose_options_of(cfg, opts, e)
      if (.not. allocated(e)) call diagnose_run(cfg, opts, res, e)
      call check_message(error, e, '&diagnose: holdout: the held-out set is empty')
      if (allocated(error)) return
      ! A test held out twice, and gamma3 named alone
      call read_config(write_text('diag-twice-held.nml', [character(len=100) :: model_groups, &
         "&fit fitted = 'B' /", "&diagnose holdout = 'b', 'b' /", tests]), cfg, e)
      call check_message(error, e, "&diagnose: holdout names 'b' twice")
      if (allocated(error)) return
      call read_config(write_text('diag-gamma3.nml', [character(len=100) :: model_groups, &
         "&fit fitted = 'B' /", "&diagnose holdout = 'b', gamma3 = -1 /", tests]), cfg, e)
      call check_message(error, e, '&diagnose: gamma3 = -1.000 must be > 0')
      if (allocated(error)) return
      ! The command checks it before it makes its folder and journal: nothing is left behind
      call execute_command_line('rm -rf '//scratch_dir//'/diag-empty-out')
      call diagnose_command(scratch_dir//'/diag-empty.nml', scratch_dir//'/diag-empty-out', '', lines, e)
      call check_message(error, e, '&diagnose: holdout: the held-out set is empty')
      if (allocated(error)) return
      call check(error, .not. file_exists(scratch_dir//'/diag-empty-out'), &
                 'the refused diagnosis left no output folder (nor diagnose.journal)')
      if (allocated(error)) return
      ! A held-out test's missing data file, a specimen without replicates and --resume
      ! without a journal are found before the folder is made too
      call write_text_file('diag-nofile.nml', [character(len=100) :: model_groups, &
         "&fit fitted = 'B' /", "&diagnose holdout = 'b' /", tests(1), &
         "&test name = 'b', history = 'relaxation', data_file = 'not-there.txt' /"])
      call execute_command_line('rm -rf '//scratch_dir//'/diag-nofile-out')
      call diagnose_command(scratch_dir//'/diag-nofile.nml', scratch_dir//'/diag-nofile-out', '', lines, e)
      call check_message(error, e, 'not-there.txt')
      if (allocated(error)) return
      call check(error, .not. file_exists(scratch_dir//'/diag-nofile-out'), &
                 'a missing held-out file left no output folder')
      if (allocated(error)) return
      call write_text_file('diag-single.nml', [character(len=100) :: model_groups, &
         "&fit fitted = 'B' /", "&diagnose specimen = 'a' /", tests(1)])
      call execute_command_line('rm -rf '//scratch_dir//'/diag-single-out')
      call diagnose_command(scratch_dir//'/diag-single.nml', scratch_dir//'/diag-single-out', '', lines, e)
      call check_message(error, e, 'at least one replicate')
      if (allocated(error)) return
      call check(error, .not. file_exists(scratch_dir//'/diag-single-out'), &
                 'a specimen without replicates left no output folder')
      if (allocated(error)) return
      call write_text_file('diag-resume.nml', [character(len=100) :: model_groups, &
         "&fit fitted = 'B' /", "&diagnose holdout = 'b' /", tests])
      call execute_command_line('rm -rf '//scratch_dir//'/diag-resume-out')
      call diagnose_command(scratch_dir//'/diag-resume.nml', scratch_dir//'/diag-resume-out', '', lines, e, &
                            mode='resume')
      call check_message(error, e, 'no journal to resume')
      if (allocated(error)) return
      call check(error, .not. file_exists(scratch_dir//'/diag-resume-out'), &
                 '--resume without a journal left no output folder')
      if (allocated(error)) return
      call read_config(write_text('diag-all.nml', [character(len=100) :: model_groups, &
         "&fit fitted = 'B' /", "&diagnose holdout = 'a', 'b' /", tests]), cfg, e)
      if (.not. allocated(e)) call diagnose_options_of(cfg, opts, e)
      if (.not. allocated(e)) call diagnose_run(cfg, opts, res, e)
      call check_message(error, e, 'every test is held out')
      if (allocated(error)) return
   contains
      subroutine write_text_file(name, text)
         character(len=*), intent(in) :: name, text(:)
         character(len=:), allocatable :: path
         path = write_text(name, text)
      end subroutine write_text_file
   end subroutine test_bad_inputs

   !> Relaxation data made with the model_groups constants (B = 1e15), every stress times
   !> scale, written to the scratch file name
   !> On a model that does not give the diagnosis its drag and back stress (Chaboche), the
   !> effects on them and, without an activation energy, the temperature offset cannot act:
   !> considered, each would be a refit of the constants alone under its name (on Alloy 617
   !> data 'initial' and 'softening' lowered BIC by 91 that way). They are left out by default
   !> and refused when named; scatter keeps its modulus factor and holds its drag factor at 0
   subroutine test_inert_effects(error)
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: e
      type(run_config) :: cfg
      type(diagnose_options) :: opts
      type(fit_problem) :: prob
      type(effect_problem) :: ep
      character(len=100), parameter :: chab(4) = [character(len=100) :: &
         "&model name = 'chaboche', units = 'MPa', temperature = 1223.15, tm = 1630.0, youngs = 144000.0 /", &
         "&constants s0 = 10, eta = 500, n = 5, q = 30, b = 20, c1 = 8e4, g1 = 1500, c2 = 5e3,", &
         "  g2 = 60, a1 = 0, m1 = 1, a2 = 1e-8, m2 = 3 /", "&fit fitted = 'eta', 'n' /"]
      character(len=100), parameter :: tests(2) = [character(len=100) :: &
         "&test name = 'a', history = 'relaxation', data_file = 'a.txt' /", &
         "&test name = 'b', history = 'relaxation', data_file = 'a.txt' /"]
      integer :: nt
      call write_relaxation_data('a.txt', 1.0_dp, e)
      if (.not. allocated(e)) call read_config(write_text('diag-inert.nml', [character(len=100) :: chab, &
         "&diagnose holdout = 'b' /", tests]), cfg, e)
      if (.not. allocated(e)) call diagnose_options_of(cfg, opts, e)
      call check(error, .not. allocated(e), 'the Chaboche deck is read')
      if (allocated(error)) return
      call check(error, all(opts%inert == [effect_index('temperature'), effect_index('initial'), &
         effect_index('softening')]), 'temperature, initial and softening left out of the Chaboche diagnosis')
      if (allocated(error)) return
      call check(error, size(opts%effects) == n_effects - 3 .and. .not. any(opts%effects == effect_index('initial')), &
         'the other six considered')
      if (allocated(error)) return
      call check(error, index(opts%inert_why(1), 'do not follow the temperature') > 0 .and. &
         index(opts%inert_why(2), 'chaboche') > 0, 'each says why: '//trim(opts%inert_why(1)))
      if (allocated(error)) return
      ! Scatter acts through E on any model, through the initial drag on the Miller model only
      call setup_problem(cfg, prob, e)
      call check(error, .not. allocated(e), 'problem set up')
      if (allocated(error)) return
      nt = size(prob%targets)
      call new_effect_problem(prob, [1], effect_index('scatter'), test_effects(), 100.0_dp, ep)
      call check(error, all(ep%pfree(:nt)) .and. .not. any(ep%pfree(nt + 1:)) .and. size(ep%pfree) == 2*nt, &
         'scatter: dE/E free, dD0/D0 held on the Chaboche model')
      if (allocated(error)) return
      ! Named, they are input errors naming the group and variable
      call read_config(write_text('diag-inert2.nml', [character(len=100) :: chab, &
         "&diagnose holdout = 'b', effects = 'lag', 'softening' /", tests]), cfg, e)
      if (.not. allocated(e)) call diagnose_options_of(cfg, opts, e)
      call check_message(error, e, "&diagnose: effects: 'softening' does not act on this model")
      if (allocated(error)) return
      call read_config(write_text('diag-inert3.nml', [character(len=100) :: chab, &
         "&diagnose holdout = 'b', rows = 'none', 'initial' /", tests]), cfg, e)
      if (.not. allocated(e)) call diagnose_options_of(cfg, opts, e)
      call check_message(error, e, "&diagnose: rows: 'initial' does not act on this model")
      if (allocated(error)) return
      ! With an activation energy the rates follow the temperature; the Miller model takes all
      call read_config(write_text('diag-inert4.nml', [character(len=140) :: chab(1)(:len_trim(chab(1)) - 1)// &
         ' activation = 95000.0 /', chab(2:), "&diagnose holdout = 'b' /", tests]), cfg, e)
      call check(error, .not. allocated(e), 'Chaboche with activation read')
      if (allocated(error)) return
      call check(error, effect_acts(cfg%model, effect_index('temperature')) .and. &
         .not. effect_acts(cfg%model, effect_index('scatter'), 2), 'activation: the temperature offset acts')
      if (allocated(error)) return
      call read_config(write_text('diag-inert5.nml', [character(len=100) :: model_groups, &
         "&fit fitted = 'B' /", "&diagnose holdout = 'b' /", tests]), cfg, e)
      if (.not. allocated(e)) call diagnose_options_of(cfg, opts, e)
      call check(error, .not. allocated(e), 'Miller deck read')
      if (allocated(error)) return
      call check(error, size(opts%effects) == n_effects .and. size(opts%inert) == 0, &
         'every effect acts on the Miller model')
   end subroutine test_inert_effects

   !> The baseline of the global stage starts from the Latin-hypercube points and from each
   !> refit's constants (within the box): a refit that ends lower by its constants alone then
   !> lowers the reference, not the effect's BIC
   subroutine test_global_baseline_starts(error)
      type(error_type), allocatable, intent(out) :: error
      type(diagnose_result) :: res
      real(dp), allocatable :: xs(:, :)
      allocate (res%x_global(2, 3), res%effects(3))
      res%x_global = reshape([1.0_dp, 2.0_dp, 3.0_dp, 4.0_dp, 5.0_dp, 6.0_dp], [2, 3])
      res%effects%refitted = [.true., .false., .true.]
      res%effects(1)%c = [10.0_dp, 1.0e3_dp]
      res%effects(2)%c = [1.0_dp, 1.0_dp]
      res%effects(3)%c = [1.0e9_dp, 1.0e-9_dp]
      xs = global_baseline_starts(res, [-1.0_dp, -1.0_dp], [7.0_dp, 7.0_dp])
      call check(error, size(xs, 2) == 5, 'three Latin-hypercube points and two refits: 5 starts, not '// &
                 str(size(xs, 2)))
      if (allocated(error)) return
      call check(error, all(abs(xs(:, 1:3) - res%x_global) < 1.0e-12_dp) .and. &
                 all(abs(xs(:, 4) - [1.0_dp, 3.0_dp]) < 1.0e-12_dp) .and. &
                 all(abs(xs(:, 5) - [7.0_dp, -1.0_dp]) < 1.0e-12_dp), &
                 'the refits'' constants as log10, within the box')
   end subroutine test_global_baseline_starts

   subroutine write_relaxation_data(name, scale, e)
      character(len=*), intent(in) :: name
      real(dp), intent(in) :: scale
      type(uerror), allocatable, intent(out) :: e
      type(run_config) :: c
      type(sim_result) :: sim
      character(len=100), allocatable :: rows(:)
      character(len=:), allocatable :: path
      integer :: i
      call read_config(write_text('diag-gen.nml', [character(len=100) :: model_groups, &
         "&test name = 'a', history = 'relaxation' /"]), c, e)
      if (allocated(e)) return
      call simulate_cvode(c%model, c%tests(1)%hist, output_times(c%tests(1)%hist, 1.0_dp), &
                          c%solver, sim, e)
      if (allocated(e)) return
      allocate (rows(size(sim%t) + 1))
      rows(1) = 'time stress'
      do i = 1, size(sim%t)
         write (rows(i + 1), '(2es24.15)') sim%t(i), scale*sim%stress(i)
      end do
      path = write_text(name, rows)
   end subroutine write_relaxation_data

   !> The baseline is fitted to the fit tests alone: a held-out data file 30 % off changes
   !> none of its figures (constants, objective, noise part, gap and floor of the fit tests)
   subroutine test_held_out_unused(error)
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: e
      type(run_config) :: cfg
      type(diagnose_options) :: opts
      type(diagnose_context) :: ctx
      type(diagnose_result) :: r1, r2
      real(dp), parameter :: scale(2) = [1.0_dp, 1.3_dp]
      integer :: k
      do k = 1, 2
         call write_relaxation_data('fit.txt', 1.0_dp, e)
         if (.not. allocated(e)) call write_relaxation_data('held.txt', scale(k), e)
         if (.not. allocated(e)) call read_config(write_text('diag-held.nml', [character(len=100) :: &
            model_groups, "&fit fitted = 'B', 'n', method = 'lm' /", "&diagnose holdout = 'held' /", &
            "&test name = 'fit', history = 'relaxation', data_file = 'fit.txt' /", &
            "&test name = 'held', history = 'relaxation', data_file = 'held.txt' /"]), cfg, e)
         if (.not. allocated(e)) call diagnose_options_of(cfg, opts, e)
         if (k == 1 .and. .not. allocated(e)) call diagnose_baseline(cfg, opts, ctx, r1, e)
         if (k == 2 .and. .not. allocated(e)) call diagnose_baseline(cfg, opts, ctx, r2, e)
         call check(error, .not. allocated(e), 'baseline failed')
         if (allocated(error)) return
      end do
      ! The held-out prediction does see the change
      call check(error, r2%per_test0(2) > 10.0_dp*r1%per_test0(2), 'held-out data not read')
      if (allocated(error)) return
      call check(error, all(r1%c == r2%c) .and. r1%f0 == r2%f0 .and. r1%per_test0(1) == r2%per_test0(1) &
                 .and. r1%noise_fit == r2%noise_fit .and. r1%gap_fit == r2%gap_fit .and. &
                 r1%floor_fit == r2%floor_fit .and. r1%noise(1) == r2%noise(1), &
                 'a baseline figure changed with the held-out data')
   end subroutine test_held_out_unused

   !> The starts of a refit side by side on two threads (tasks), each point's two tests tasks
   !> too, end where they end one after the other on one thread, bit for bit, with the same
   !> simulations counted
   subroutine test_starts_threads(error)
      type(error_type), allocatable, intent(out) :: error
      type(run_config) :: cfg
      type(diagnose_context) :: ctx
      type(effect_problem) :: ep(2)
      type(optimum_type) :: opt(2)
      real(dp), allocatable :: xs(:, :), lo(:), hi(:), fs(:, :)
      integer :: nevals(2), k, nthreads
      call relaxation_baseline('diag-starts', cfg, ctx, error)
      if (allocated(error)) return
      xs = global_points(cfg, ctx%prob, 4)
      allocate (fs(size(xs, 2), 2))
      nthreads = omp_get_max_threads()
      do k = 1, 2
         call omp_set_num_threads(k)
         call new_effect_problem(ctx%prob, [1, 2], 0, ctx%eff_base, ctx%peak, ep(k))
         call ep(k)%bounds(lo, hi)
         opt(k)%f = huge(1.0_dp)
         nevals(k) = 0
         call best_of_starts(ep(k), xs, lo, hi, ctx%h, 400, opt(k), nevals(k), fs(:, k))
      end do
      call omp_set_num_threads(nthreads)
      call check(error, allocated(opt(1)%x) .and. allocated(opt(2)%x), 'no start ended')
      if (allocated(error)) return
      call check(error, all(fs(:, 1) == fs(:, 2)) .and. all(opt(1)%x == opt(2)%x) .and. &
                 opt(1)%f == opt(2)%f, 'the starts ended elsewhere on two threads: '// &
                 real_str(opt(1)%f, 'es23.16')//' against '//real_str(opt(2)%f, 'es23.16'))
      if (allocated(error)) return
      call check(error, nevals(1) == nevals(2) .and. ep(1)%nevals == ep(2)%nevals .and. nevals(1) > 0, &
                 'simulations counted differently on two threads')
   end subroutine test_starts_threads

   !> The baseline of B, n and A1 fitted to a relaxation test (name.txt), another held out
   !> (the same data), from the deck name.nml
   subroutine relaxation_baseline(name, cfg, ctx, error)
      character(len=*), intent(in) :: name
      type(run_config), intent(out) :: cfg
      type(diagnose_context), intent(out) :: ctx
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: e
      type(diagnose_options) :: opts
      type(diagnose_result) :: res
      call write_relaxation_data(name//'.txt', 1.0_dp, e)
      if (.not. allocated(e)) call read_config(write_text(name//'.nml', [character(len=100) :: &
         model_groups, "&fit fitted = 'B', 'n', 'A1', method = 'lm' /", "&diagnose holdout = 'held' /", &
         "&test name = 'fit', history = 'relaxation', data_file = '"//name//".txt' /", &
         "&test name = 'held', history = 'relaxation', data_file = '"//name//".txt' /"]), cfg, e)
      if (.not. allocated(e)) call diagnose_options_of(cfg, opts, e)
      if (.not. allocated(e)) call diagnose_baseline(cfg, opts, ctx, res, e)
      call check(error, .not. allocated(e), 'baseline failed')
   end subroutine relaxation_baseline

   !> A Levenberg-Marquardt run asked for again takes the outcome it had, bit for bit, and
   !> simulates nothing: starts 1-2, then 2-4, give for 2-4 what best_of_starts gives alone,
   !> with the simulations of starts 3-4 only; a run of another problem is made. Journaled and
   !> then replayed with a new memo, the same calls give the same outcomes and counts, and
   !> start 1 again simulates nothing (the replayed units fill the memo as computed ones do).
   subroutine test_memo(error)
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: e
      type(run_config) :: cfg
      type(diagnose_context) :: ctx
      type(effect_problem) :: ep, ep2
      type(optimum_type) :: ref, opt, single, first(2)
      type(run_memo), target :: memo, memo2
      type(run_memo), pointer :: mp
      type(diagnose_journal), target :: jfile(2)
      type(diagnose_journal), pointer :: jr
      real(dp), allocatable :: xs(:, :), lo(:), hi(:), fref(:), f(:)
      integer :: nev, n0, sims34, pass, d12(2)
      character(len=*), parameter :: journal = scratch_dir//'/diag-memo.journal'
      call baseline_starts('diag-memo', 4, cfg, ctx, ep, xs, lo, hi, error)
      if (allocated(error)) return
      ! Without a memo: starts 2-4, and 3-4 alone
      allocate (fref(3))
      nev = 0
      call best_of_starts(ep, xs(:, 2:4), lo, hi, ctx%h, 400, ref, nev, fref)
      n0 = ep%nevals
      nev = 0
      call best_of_starts(ep, xs(:, 3:4), lo, hi, ctx%h, 400, single, nev)
      sims34 = ep%nevals - n0
      do pass = 1, 2
         ! pass 1 computes into a journal, pass 2 replays it with a new memo
         if (pass == 1) then
            call execute_command_line('rm -f '//journal)
            call jfile(1)%open(journal, 'memo test', 'start', e)
            mp => memo
         else
            call jfile(2)%open(journal, 'memo test', 'resume', e)
            mp => memo2
         end if
         call check(error, .not. allocated(e), 'journal')
         if (allocated(error)) return
         jr => jfile(pass)
         n0 = ep%nevals
         nev = 0
         call starts_unit(jr, ep, xs(:, 1:2), lo, hi, ctx%h, 400, first(pass), nev, e, memo=mp)
         call check(error, .not. allocated(e), 'starts 1-2')
         if (allocated(error)) return
         ! (a replayed unit counts the simulations it had)
         d12(pass) = ep%nevals - n0
         n0 = ep%nevals
         nev = 0
         allocate (f(3))
         call starts_unit(jr, ep, xs(:, 2:4), lo, hi, ctx%h, 400, opt, nev, e, f, memo=mp)
         call check(error, .not. allocated(e), 'starts 2-4')
         if (allocated(error)) return
         call check(error, opt%f == ref%f .and. all(opt%x == ref%x) .and. all(f == fref), &
                    'starts 2-4 with start 2 from the memo end elsewhere: '//real_str(opt%f, 'es23.16')// &
                    ' against '//real_str(ref%f, 'es23.16'))
         if (allocated(error)) return
         call check(error, ep%nevals - n0 == sims34, 'starts 2-4 after 1-2 simulated '// &
                    real_str(real(ep%nevals - n0, dp), 'f8.0')//' times, starts 3-4 alone '// &
                    real_str(real(sims34, dp), 'f8.0'))
         if (allocated(error)) return
         deallocate (f)
         ! Start 1 again as a run of its own: from the memo, no simulation
         n0 = ep%nevals
         call lm_unit(jr, ep, xs(:, 1), lo, hi, ctx%h, lm_ftol, lm_itermax, 400, opt, e, memo=mp)
         call check(error, .not. allocated(e) .and. ep%nevals == n0 .and. opt%nevals == 0, &
                    'start 1 again was simulated')
         if (allocated(error)) return
         call jfile(pass)%close(e)
      end do
      call check(error, first(1)%f == first(2)%f .and. all(first(1)%x == first(2)%x) .and. &
                 d12(1) == d12(2) .and. d12(1) > 0, 'the replay ended elsewhere')
      if (allocated(error)) return
      ! Another problem (every test): made, not taken
      call new_effect_problem(ctx%prob, [1, 2], 0, ctx%eff_base, ctx%peak, ep2)
      n0 = ep2%nevals
      jr => null()
      call lm_unit(jr, ep2, xs(:, 1), lo, hi, ctx%h, lm_ftol, lm_itermax, 400, opt, e, memo=mp)
      call check(error, .not. allocated(e) .and. ep2%nevals > n0, 'a run of another problem was taken from the memo')
      call execute_command_line('rm -f '//journal)
   end subroutine test_memo

   !> The relaxation baseline's problem without an effect, its bounds and n Latin-hypercube
   !> starts of its constants
   subroutine baseline_starts(name, n, cfg, ctx, ep, xs, lo, hi, error)
      character(len=*), intent(in) :: name
      integer, intent(in) :: n
      type(run_config), intent(out) :: cfg
      type(diagnose_context), intent(out) :: ctx
      type(effect_problem), intent(out) :: ep
      real(dp), allocatable, intent(out) :: xs(:, :), lo(:), hi(:)
      type(error_type), allocatable, intent(out) :: error
      call relaxation_baseline(name, cfg, ctx, error)
      if (allocated(error)) return
      xs = global_points(cfg, ctx%prob, n)
      call new_effect_problem(ctx%prob, ctx%ifit, 0, ctx%eff_base, ctx%peak, ep)
      call ep%bounds(lo, hi)
   end subroutine baseline_starts

   !> A journal's unit is replayed only for the request it was made for: a resumed run that asks
   !> its units in another order, or from other starts (a journal of another build), is
   !> refused at the first unit that parts, with an input error naming the journal
   subroutine test_unit_request(error)
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: e
      type(run_config) :: cfg
      type(diagnose_context) :: ctx
      type(effect_problem) :: ep
      type(optimum_type) :: opt(3)
      type(diagnose_journal), target :: jfile
      type(diagnose_journal), pointer :: jr
      real(dp), allocatable :: xs(:, :), lo(:), hi(:)
      integer :: nev, pass
      character(len=*), parameter :: journal = scratch_dir//'/diag-request.journal'
      call baseline_starts('diag-request', 3, cfg, ctx, ep, xs, lo, hi, error)
      if (allocated(error)) return
      jr => jfile
      call execute_command_line('rm -f '//journal)
      ! Made: a run from start 1, then starts 2-3
      call jfile%open(journal, 'request test', 'start', e)
      if (.not. allocated(e)) call lm_unit(jr, ep, xs(:, 1), lo, hi, ctx%h, lm_ftol, lm_itermax, 400, opt(1), e)
      nev = 0
      if (.not. allocated(e)) call starts_unit(jr, ep, xs(:, 2:3), lo, hi, ctx%h, 400, opt(2), nev, e)
      if (.not. allocated(e)) call jfile%close(e)
      call check(error, .not. allocated(e), 'the journal was not made')
      if (allocated(error)) return
      do pass = 1, 2
         call jfile%open(journal, 'request test', 'resume', e)
         call check(error, .not. allocated(e), 'the journal did not open for resume')
         if (allocated(error)) return
         if (pass == 1) then
            ! The same requests: replayed to the same end
            call lm_unit(jr, ep, xs(:, 1), lo, hi, ctx%h, lm_ftol, lm_itermax, 400, opt(3), e)
            call check(error, .not. allocated(e), 'the same first request was refused')
            if (allocated(error)) return
            call check(error, opt(3)%f == opt(1)%f .and. all(opt(3)%x == opt(1)%x), &
                       'the replayed run ended elsewhere')
            if (allocated(error)) return
            ! The second unit asked with other starts (3-2, not 2-3)
            nev = 0
            call starts_unit(jr, ep, xs(:, [3, 2]), lo, hi, ctx%h, 400, opt(3), nev, e)
         else
            ! The first unit asked from another start
            call lm_unit(jr, ep, xs(:, 2), lo, hi, ctx%h, lm_ftol, lm_itermax, 400, opt(3), e)
         end if
         call check(error, allocated(e), 'pass '//str(pass)//': a unit made for another request was replayed')
         if (allocated(error)) return
         call check(error, e%stat == 1 .and. index(e%message, journal//': cannot resume: its unit '// &
                    str(3 - pass)//' was made') == 1 .and. index(e%message, '--force') > 0, &
                    'not the refusal asked for: '//e%message)
         if (allocated(error)) return
         deallocate (e)
         call jfile%close(e)
      end do
      call execute_command_line('rm -f '//journal)
   end subroutine test_unit_request

   !> The constants given are only a start: from B three times too high (an unconverged fit)
   !> the baseline comes back to the B the data were made with
   subroutine test_unconverged_start(error)
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: e
      type(run_config) :: cfg
      type(diagnose_options) :: opts
      type(diagnose_context) :: ctx
      type(diagnose_result) :: res
      call write_relaxation_data('a.txt', 1.0_dp, e)
      if (.not. allocated(e)) call read_config(write_text('diag-unconverged.nml', [character(len=100) :: &
         "&model temperature = 866.15, tm = 1800.0, youngs = 22.5e3, poisson = 0.3 /", &
         "&constants a1 = 0.8, a2 = 7.42e-5, b = 3.0e15, c2 = 0.1, h1 = 280.0, h2 = 100.0,", &
         "  n = 5.8, q = 91000.0 /", "&fit fitted = 'B', method = 'lm' /", "&diagnose holdout = 'b' /", &
         "&test name = 'a', history = 'relaxation', data_file = 'a.txt' /", &
         "&test name = 'b', history = 'relaxation', data_file = 'a.txt' /"]), cfg, e)
      if (.not. allocated(e)) call diagnose_options_of(cfg, opts, e)
      if (.not. allocated(e)) call diagnose_baseline(cfg, opts, ctx, res, e)
      call check(error, .not. allocated(e), 'baseline failed from an unconverged start')
      if (allocated(error)) return
      call check(error, abs(res%c(1)/1.0e15_dp - 1.0_dp) < 1.0e-3_dp, 'baseline B = '// &
                 real_str(res%c(1), 'es12.5')//', data made with 1e15')
   end subroutine test_unconverged_start

   !> Parsimony of the verdict: two confirmed effects, compliance (1 parameter) and scatter
   !> (4, per test, BIC 14 lower): both leave only noise, so the simpler leads and the report
   !> names the other with the BIC that tells them apart; when compliance leaves a structured gap and scatter is
   !> 14 lower, scatter leads alone; within 10 of BIC, the simpler leads. Its words: "explains"
   !> where the rest of a gap lies below its floor, "partly explains" where it does not
   subroutine test_parsimony(error)
      type(error_type), allocatable, intent(out) :: error
      type(diagnose_result) :: res, res3
      call verdict_case(10.0_dp, 5.0_dp, 2, res)
      res%effects(1) = outcome(4, 'scatter', 4, -114.0_dp, 0.999_dp, 0.01_dp)
      res%effects(2) = outcome(1, 'compliance', 1, -100.0_dp, 0.999_dp, 0.01_dp)
      call conclude(res)
      call check(error, res%leading == 2 .and. size(res%alike) == 2, 'both leave noise: '// &
                 'compliance must lead, alike with scatter; verdict: '//res%verdict)
      if (allocated(error)) return
      ! (14 in BIC apart, alike by both leaving noise: named with the BIC that tells them apart)
      call check(error, index(res%verdict, 'scatter (BIC -14.0) explains it to the noise level too') > 0 .and. &
                 index(res%verdict, 'compliance is the simplest') > 0, res%verdict)
      if (allocated(error)) return
      ! A gain and a temperature offset of one parameter per test, a scatter of two far better
      ! by BIC, all at the noise level: the gain leads as the simplest, by BIC only against
      ! the temperature (once said "leads by BIC", as if against scatter too)
      call verdict_case(10.0_dp, 5.0_dp, 3, res3)
      res3%effects(1) = outcome(10, 'gain', 2, -100.0_dp, 0.999_dp, 0.01_dp)
      res3%effects(2) = outcome(3, 'temperature', 2, -56.0_dp, 0.999_dp, 0.01_dp)
      res3%effects(3) = outcome(4, 'scatter', 4, -267.0_dp, 0.999_dp, 0.01_dp)
      call conclude(res3)
      call check(error, res3%leading == 1 .and. size(res3%alike) == 3 .and. &
                 index(res3%verdict, 'gain is the simplest with temperature, and leads by BIC among those') > 0 .and. &
                 index(res3%verdict, 'scatter (BIC -167.0)') > 0, res3%verdict)
      if (allocated(error)) return
      ! Compliance leaves a structured gap (70 % removed): strong evidence for scatter
      res%effects(2)%shrink_fit = 0.7_dp
      res%effects(2)%held_gap = 2.0_dp
      call conclude(res)
      call check(error, res%leading == 1 .and. size(res%alike) == 1, 'strong evidence: scatter '// &
                 'must lead alone; verdict: '//res%verdict)
      if (allocated(error)) return
      ! Within 10 of BIC: the simpler leads, and its partial removal is said so
      res%effects(1)%dbic = -105.0_dp
      call conclude(res)
      call check(error, res%leading == 2 .and. index(res%verdict, 'compliance partly explains') == 1, &
                 'within 10 of BIC: '//res%verdict)
      if (allocated(error)) return
      ! 73.9 % of a held-out gap of 2.3 floors removed, its rest (0.6) below the floor and the
      ! part removed above it: all that the data resolve, and the words say so
      res%gap_held = 2.3_dp
      res%effects(1) = outcome(4, 'scatter', 4, -50.0_dp, 0.999_dp, 0.6_dp)
      res%effects(2) = outcome(1, 'compliance', 1, -100.0_dp, 0.999_dp, 0.6_dp)
      call conclude(res)
      call check(error, res%leading == 2 .and. index(res%verdict, 'compliance explains the gap') == 1 .and. &
                 index(res%verdict, '73.9 % on the held-out tests, the rest below its floor') > 0, &
                 'rest below the floor: '//res%verdict)
      if (allocated(error)) return
      ! Its rest above the floor (1.2): "partly", with no such words
      res%effects(1) = outcome(4, 'scatter', 4, -50.0_dp, 0.999_dp, 1.2_dp)
      res%effects(2) = outcome(1, 'compliance', 1, -100.0_dp, 0.999_dp, 1.2_dp)
      call conclude(res)
      call check(error, res%leading == 2 .and. index(res%verdict, 'compliance partly explains') == 1 .and. &
                 index(res%verdict, 'below its floor') == 0, 'rest above the floor: '//res%verdict)
      if (allocated(error)) return
      ! 7 % of the fit tests' gap and 4 % of the held-out one: a lower BIC, little explained
      res%effects(1) = outcome(4, 'scatter', 4, -50.0_dp, 0.07_dp, 2.2_dp)
      res%effects(2) = outcome(1, 'compliance', 1, -100.0_dp, 0.07_dp, 2.2_dp)
      call conclude(res)
      call check(error, res%leading == 2 .and. index(res%verdict, 'compliance explains little of the gap') == 1, &
                 'shares below 30 %: '//res%verdict)
   contains
      function outcome(k, name, q, dbic, shrink, held_gap) result(e)
         integer, intent(in) :: k, q
         character(len=*), intent(in) :: name
         real(dp), intent(in) :: dbic, shrink, held_gap
         type(effect_outcome) :: e
         e%k = k
         e%name = name
         e%q = q
         e%dbic = dbic
         e%refitted = .true.
         e%significant = .true.
         e%confirmed = .true.
         e%shrink_fit = shrink
         e%shrink_held = 1.0_dp - held_gap/res%gap_held
         e%held_gap = held_gap
         e%worse = [.false., .false., .false.]
      end function outcome
   end subroutine test_parsimony

   !> A result to draw a verdict on: tests a and b fitted, c held out, their structured gaps
   !> gap_fit and gap_held against floors of 1, no regions, n effects to be set
   subroutine verdict_case(gap_fit, gap_held, n, res)
      real(dp), intent(in) :: gap_fit, gap_held
      integer, intent(in) :: n
      type(diagnose_result), intent(out) :: res
      res%names = [character(len=64) :: 'a', 'b', 'c']
      res%held = [.false., .false., .true.]
      res%gap_fit = gap_fit
      res%floor_fit = 1.0_dp
      res%gap_held = gap_held
      res%floor_held = 1.0_dp
      allocate (res%regions(0))
      allocate (res%effects(n))
   end subroutine verdict_case

   !> Nothing significant, yet a refit that lowers BIC by 6 to 10 (strong evidence, short of
   !> bic_margin): the verdict of no effect names it as a hint (the lowest such; not one that
   !> lowers BIC by less than 6, nor one that raises it), and says nothing when none does
   subroutine test_weak_evidence(error)
      type(error_type), allocatable, intent(out) :: error
      type(diagnose_result) :: res
      call verdict_case(0.5_dp, 0.5_dp, 3, res)
      res%effects(1) = weak(1, 'compliance', 3.0_dp, -1.0_dp)
      res%effects(2) = weak(9, 'drift', -8.3_dp, -26.2_dp)
      res%effects(3) = weak(2, 'lag', -2.0_dp, -7.9_dp)
      call conclude(res)
      call check(error, res%leading == 0 .and. index(res%verdict, 'no significant effect') == 1, res%verdict)
      if (allocated(error)) return
      call check(error, index(res%verdict, '; drift lowers BIC by 8.3 (AIC by 26.2), short of the 10 a '// &
                 'finding needs: a hint, not a finding') > 0 .and. index(res%verdict, 'lag lowers') == 0 .and. &
                 index(res%verdict, 'compliance lowers') == 0, res%verdict)
      if (allocated(error)) return
      res%effects(2)%dbic = -5.5_dp
      call conclude(res)
      call check(error, index(res%verdict, 'a hint') == 0, 'no refit lowers BIC by 6: '//res%verdict)
   contains
      function weak(k, name, dbic, daic) result(e)
         integer, intent(in) :: k
         character(len=*), intent(in) :: name
         real(dp), intent(in) :: dbic, daic
         type(effect_outcome) :: e
         e%k = k
         e%name = name
         e%q = 1
         e%dbic = dbic
         e%daic = daic
         e%refitted = .true.
         e%worse = [.false., .false., .false.]
      end function weak
   end subroutine test_weak_evidence

   !> The verdict says how large the leader is and where it acts: its fitted values with
   !> their intervals (a per-test effect's only of the tests that show it where its BIC
   !> counts only those; a value at its search bound said once, by the note of the bounds)
   !> and, of the regions with a structured residual, the one whose gap it removes most
   subroutine test_verdict_size(error)
      type(error_type), allocatable, intent(out) :: error
      type(diagnose_result) :: res
      call verdict_case(10.0_dp, 5.0_dp, 1, res)
      res%stress_unit = 'MPa'
      ! (c's elastic points carry no structured residual: a fall there is no place it acts)
      res%regions = [region('a', 'hold', 3.0_dp), region('b', 'loading', 4.0_dp), region('a', 'whole test', 9.0_dp), &
                     region('c', 'elastic', 5.0_dp)]
      res%regions(4)%structured = .false.
      res%effects(1)%k = 9
      res%effects(1)%name = 'drift'
      res%effects(1)%q = 2
      res%effects(1)%dbic = -80.0_dp
      res%effects(1)%confirmed = .true.
      res%effects(1)%refitted = .true.
      res%effects(1)%shrink_fit = 0.9_dp
      res%effects(1)%shrink_held = 0.9_dp
      res%effects(1)%held_gap = 0.5_dp
      res%effects(1)%worse = [.false., .false., .false.]
      res%effects(1)%p = [5.4e-7_dp, 1.0e-9_dp]
      res%effects(1)%p_lo = [4.48e-7_dp, -3.0e-8_dp]
      res%effects(1)%p_hi = [6.32e-7_dp, 3.2e-8_dp]
      res%effects(1)%pname = [character(len=81) :: 'd a', 'd b']
      res%effects(1)%punit = [character(len=12) :: '1/s', '1/s']
      res%effects(1)%p_counted = [.true., .false.]
      res%effects(1)%shown_on = 'a'
      res%effects(1)%dbic_all = -70.0_dp
      ! (the hold's gap 3.0 -> 0.1 removed most; the loading's 4.0 -> 3.5 less; whole tests not regions)
      res%effects(1)%regions = [region('a', 'hold', 0.1_dp), region('b', 'loading', 3.5_dp), &
                                region('a', 'whole test', 0.0_dp), region('c', 'elastic', 0.0_dp)]
      call conclude(res)
      call check(error, res%leading == 1 .and. index(res%verdict, '; fitted d a = 5.40E-07 [4.48E-07, 6.32E-07] '// &
                 '1/s; it acts most on a hold (structured gap 3.00E+00 -> 1.00E-01)') > 0 .and. &
                 index(res%verdict, 'd b') == 0, res%verdict)
      if (allocated(error)) return
      ! Its BIC counting every test's values, both are given
      res%effects(1)%dbic_all = -90.0_dp
      call conclude(res)
      call check(error, index(res%verdict, '6.32E-07] 1/s, d b = 1.00E-09 [-3.00E-08, 3.20E-08] 1/s;') > 0, res%verdict)
      if (allocated(error)) return
      ! The second at its upper search bound: said once, by the note of the bounds
      res%effects(1)%p_bound = [0, 1]
      call conclude(res)
      call check(error, index(res%verdict, '6.32E-07] 1/s; it acts') > 0 .and. &
                 index(res%verdict, 'search bound') > 0 .and. &
                 index(res%verdict, 'search bound') == index(res%verdict, 'search bound', back=.true.), res%verdict)
   contains
      function region(test, label, gap) result(r)
         character(len=*), intent(in) :: test, label
         real(dp), intent(in) :: gap
         type(region_stat) :: r
         r%test = test
         r%label = label
         r%gap = gap
         r%structured = .true.
      end function region
   end subroutine test_verdict_size

   !> Both sets' gaps below their floors: an effect that lowers BIC by 30, plausible and
   !> keeping the held-out tests at their noise level is confirmed; the same effect opening a
   !> held-out gap is not, nor is a delay below the sampling interval (nothing structured for
   !> it to remove), nor one that lowers BIC by less than bic_margin
   subroutine test_below_floors(error)
      type(error_type), allocatable, intent(out) :: error
      type(diagnose_context) :: ctx
      type(diagnose_result) :: res
      type(effect_outcome) :: e
      call below_floors_case([1000], [1.0_dp], ctx, res)
      e%q = 2
      e%f_after = exp(-(30.0_dp + 2.0_dp*log(1000.0_dp))/1000.0_dp)
      e%per_test_after = [e%f_after]
      e%held_gap = 0.01_dp
      call judge(ctx, res, e)
      call check(error, e%significant .and. e%confirmed, 'BIC -30 below the floors not confirmed')
      if (allocated(error)) return
      e%held_gap = 0.5_dp
      call judge(ctx, res, e)
      call check(error, .not. e%confirmed, 'confirmed although it opens a held-out gap')
      if (allocated(error)) return
      e%held_gap = 0.01_dp
      e%resolved = .false.
      call judge(ctx, res, e)
      call check(error, .not. e%confirmed, 'a delay below the sampling interval confirmed below the floors')
      if (allocated(error)) return
      e%resolved = .true.
      e%f_after = exp(-(5.0_dp + 2.0_dp*log(1000.0_dp))/1000.0_dp)
      e%per_test_after = [e%f_after]
      call judge(ctx, res, e)
      call check(error, .not. e%significant .and. .not. e%confirmed, 'BIC -5 confirmed')
   end subroutine test_below_floors

   !> A delay below the sampling interval that the data measure (its interval within
   !> delay_precision) and that removes the fit tests' whole structured gap is confirmed while
   !> it carries 71 % of the held-out gap (as an independent program's lag of 0.1 s under
   !> 0.5 s sampling did); not when the data leave it loose, nor when it removes 6 % of the
   !> fit tests' gap
   subroutine test_measured_delay(error)
      type(error_type), allocatable, intent(out) :: error
      type(diagnose_context) :: ctx
      type(diagnose_result) :: res
      type(effect_outcome) :: e
      call below_floors_case([1000], [1.0_dp], ctx, res)
      res%gap_fit = 10.0_dp
      res%floor_fit = 1.0_dp
      res%gap_held = 5.0_dp
      res%floor_held = 1.0_dp
      e%q = 1
      e%f_after = exp(-(1000.0_dp + log(1000.0_dp))/1000.0_dp)
      e%per_test_after = [e%f_after]
      e%shrink_fit = 1.0_dp
      e%shrink_held = 0.71_dp
      e%held_gap = 0.29_dp*res%gap_held
      e%resolved = .false.
      e%measured = .true.
      call judge(ctx, res, e)
      call check(error, e%significant .and. e%confirmed, 'a measured sub-sample delay not confirmed')
      if (allocated(error)) return
      e%measured = .false.
      call judge(ctx, res, e)
      call check(error, .not. e%confirmed, 'a loose sub-sample delay confirmed at 71 % of the held-out gap')
      if (allocated(error)) return
      e%measured = .true.
      e%shrink_fit = 0.06_dp
      call judge(ctx, res, e)
      call check(error, .not. e%confirmed, 'a measured delay removing 6 % of the fit gap confirmed')
   end subroutine test_measured_delay

   !> BIC counts each fit test's residuals in a variance of their own: a fall of 15 % in a
   !> test of 100 points whose points carry 12 times the variance of the other test's 900
   !> is not significant (100 ln 0.85 + ln 1000 = -9.3), where one pooled variance would
   !> have made it -139
   subroutine test_bic_per_test(error)
      type(error_type), allocatable, intent(out) :: error
      type(diagnose_context) :: ctx
      type(diagnose_result) :: res
      type(effect_outcome) :: e
      call below_floors_case([100, 900], [1.0_dp, 0.1_dp], ctx, res)
      e%q = 1
      e%per_test_after = [0.85_dp, 0.1_dp]
      e%f_after = sum(e%per_test_after)
      e%held_gap = 0.01_dp
      call judge(ctx, res, e)
      call check(error, abs(e%dbic - (100.0_dp*log(0.85_dp) + log(1000.0_dp))) < 1.0e-10_dp, &
                 'dBIC '//real_str(e%dbic, 'es12.5')//' is not that of each test''s own variance')
      if (allocated(error)) return
      call check(error, .not. e%significant, 'a fall within the noisy test found significant')
      if (allocated(error)) return
      ! The same share of the quiet test's sum is
      e%per_test_after = [1.0_dp, 0.085_dp]
      e%f_after = sum(e%per_test_after)
      call judge(ctx, res, e)
      call check(error, e%significant .and. abs(e%dbic - (900.0_dp*log(0.85_dp) + log(1000.0_dp))) < 1.0e-9_dp, &
                 'a 15 % fall in the quiet test: dBIC '//real_str(e%dbic, 'es12.5'))
   end subroutine test_bic_per_test

   !> A per-test effect's BIC counts the parameters of the tests that show it: three tests,
   !> one parameter each at 4.9, 0.03 and 1.0 standard errors (Wald 24, 0.0009, 1 against
   !> ln N = 7.7): the first counted, the others' chi-square 1.0009. A test of two correlated
   !> parameters (correlation 0.9, each at 1 standard error) is left out on Wald 2/1.9, not
   !> the 2 of the diagonal; two tests left out whose parameters correlate (0.9) take 2/1.9
   !> together, not 2. Where no test shows it, every parameter is counted. judge then takes
   !> the lower of the BIC with every parameter and with the counted ones and the others'
   !> chi-square: a fall of the deviance by 25 with three parameters, of which one is
   !> counted, lowers BIC by 25 - 1.0009 - 6.9 = 17.1, not by 25 - 3 x 6.9 = 4.3
   subroutine test_bic_shown(error)
      type(error_type), allocatable, intent(out) :: error
      type(diagnose_context) :: ctx
      type(diagnose_result) :: res
      type(effect_outcome) :: e
      logical, allocatable :: counted(:)
      real(dp) :: wald, cp(3, 3), lnm
      lnm = 7.7_dp
      cp = 0.0_dp
      cp(1, 1) = 1.0_dp
      cp(2, 2) = 1.0_dp
      cp(3, 3) = 1.0_dp
      call shown_groups([1, 2, 3], 3, [4.9_dp, 0.03_dp, 1.0_dp], cp, lnm, counted, wald)
      call check(error, all(counted .eqv. [.true., .false., .false.]) .and. &
                 abs(wald - (0.03_dp**2 + 1.0_dp)) < 1.0e-12_dp, &
                 'one parameter per test: counted '//merge('T', 'F', counted(1))//merge('T', 'F', counted(2))// &
                 merge('T', 'F', counted(3))//', Wald '//real_str(wald, 'es12.5'))
      if (allocated(error)) return
      ! test 1 at 5 standard errors; test 2's two parameters correlated 0.9, each at 1
      cp(2, 3) = 0.9_dp
      cp(3, 2) = 0.9_dp
      call shown_groups([1, 2, 2], 2, [5.0_dp, 1.0_dp, 1.0_dp], cp, lnm, counted, wald)
      call check(error, all(counted .eqv. [.true., .false., .false.]) .and. abs(wald - 2.0_dp/1.9_dp) < 1.0e-12_dp, &
                 'two correlated parameters of one test: Wald '//real_str(wald, 'es12.5')//' (2/1.9 from the block)')
      if (allocated(error)) return
      ! the same covariance, tests 2 and 3 one parameter each: left out together
      call shown_groups([1, 2, 3], 3, [5.0_dp, 1.0_dp, 1.0_dp], cp, lnm, counted, wald)
      call check(error, all(counted .eqv. [.true., .false., .false.]) .and. abs(wald - 2.0_dp/1.9_dp) < 1.0e-12_dp, &
                 'two tests left out whose parameters correlate: Wald '//real_str(wald, 'es12.5')//' (2/1.9)')
      if (allocated(error)) return
      ! no test shows it: every parameter counted
      call shown_groups([1, 2, 3], 3, [1.0_dp, 1.0_dp, 1.0_dp], cp, lnm, counted, wald)
      call check(error, all(counted) .and. wald == 0.0_dp, 'no test shows the effect, and not every parameter counted')
      if (allocated(error)) return
      ! judge: one test of 1000 points whose deviance falls by 25
      call below_floors_case([1000], [1.0_dp], ctx, res)
      e%q = 3
      e%per_test_after = [exp(-25.0_dp/1000.0_dp)]
      e%f_after = sum(e%per_test_after)
      e%held_gap = 0.01_dp
      call judge(ctx, res, e)
      call check(error, abs(e%dbic - (-25.0_dp + 3.0_dp*log(1000.0_dp))) < 1.0e-9_dp .and. .not. e%significant, &
                 'not computed: dBIC '//real_str(e%dbic, 'es12.5')//' is not that of every parameter')
      if (allocated(error)) return
      e%q_bic = 1
      e%wald_dropped = 1.0009_dp
      call judge(ctx, res, e)
      call check(error, abs(e%dbic - (-25.0_dp + 1.0009_dp + log(1000.0_dp))) < 1.0e-9_dp .and. e%significant .and. &
                 abs(e%dbic_all - (-25.0_dp + 3.0_dp*log(1000.0_dp))) < 1.0e-9_dp, &
                 'one of three counted: dBIC '//real_str(e%dbic, 'es12.5'))
      if (allocated(error)) return
      ! never above the BIC with every parameter counted
      e%wald_dropped = 30.0_dp
      call judge(ctx, res, e)
      call check(error, abs(e%dbic - e%dbic_all) < 1.0e-12_dp, &
                 'left-out groups that take more than they cost: dBIC '//real_str(e%dbic, 'es12.5'))
   end subroutine test_bic_shown

   !> The fit tests without a structured gap, the held-out tests with one (5 against a floor
   !> of 1): a significant, plausible effect that removes the held-out gap is confirmed while
   !> its refit's constants alone remove none of it, and not when they alone remove all of it
   !> (they wandered along what the fit tests leave loose: no evidence of the effect)
   subroutine test_loose_prediction(error)
      type(error_type), allocatable, intent(out) :: error
      type(diagnose_context) :: ctx
      type(diagnose_result) :: res
      type(effect_outcome) :: e
      call below_floors_case([1000], [1.0_dp], ctx, res)
      res%gap_held = 5.0_dp
      res%floor_held = 1.0_dp
      e%q = 1
      e%f_after = exp(-(50.0_dp + log(1000.0_dp))/1000.0_dp)
      e%per_test_after = [e%f_after]
      e%shrink_held = 1.0_dp
      e%held_gap = 0.0_dp
      e%shrink_held_constants = 0.0_dp
      call judge(ctx, res, e)
      call check(error, e%confirmed .and. .not. e%carried_by_constants, &
                 'a prediction its constants alone do not make not confirmed')
      if (allocated(error)) return
      e%shrink_held_constants = 1.0_dp
      call judge(ctx, res, e)
      call check(error, e%carried_by_constants .and. .not. e%confirmed, &
                 'a prediction its constants alone make confirmed')
      if (allocated(error)) return
      ! With a structured gap on the fit tests the effect sets the constants right: its own
      res%gap_fit = 10.0_dp
      res%floor_fit = 1.0_dp
      e%shrink_fit = 1.0_dp
      call judge(ctx, res, e)
      call check(error, e%confirmed .and. .not. e%carried_by_constants, &
                 'a prediction of constants the effect set right not confirmed')
   end subroutine test_loose_prediction

   !> A refit whose constants with the effect off fit the fit tests better than the baseline
   !> (a lower objective and a deviance lower by more than the BIC margin) leaves it behind;
   !> not within the margin, nor with a higher objective (per-test variances can lower the
   !> deviance while the sum of squares the baseline minimises rises), nor when it was not
   !> refitted, nor where the global stage found a baseline as low as those constants (every
   !> effect was judged against that one); of two, the lower deviance. Two fit tests of 100
   !> and 1000 points, a held-out one whose sums count for nothing
   subroutine test_left_behind(error)
      type(error_type), allocatable, intent(out) :: error
      type(diagnose_result) :: res
      res%npts = [100, 1000, 500]
      res%held = [.false., .false., .true.]
      res%per_test0 = [1.0_dp, 1.0_dp, 5.0_dp]
      res%f0 = 2.0_dp
      allocate (res%effects(3))
      res%effects%refitted = .true.
      ! deviances 1100 ln(0.997) = -3.3, 1000 ln(0.98) = -20.2; a held-out test far worse
      res%effects(1)%per_constants = [0.997_dp, 0.997_dp, 9.0_dp]
      res%effects(2)%per_constants = [1.0_dp, 0.98_dp, 9.0_dp]
      res%effects(3)%per_constants = [1.0_dp, 1.0_dp, 1.0_dp]
      call check(error, baseline_left_behind(res) == 2, 'a refit''s better constants not seen')
      if (allocated(error)) return
      res%effects(3)%per_constants = [0.9_dp, 0.95_dp, 1.0_dp]
      call check(error, baseline_left_behind(res) == 3, 'not the lowest deviance')
      if (allocated(error)) return
      res%effects(3)%refitted = .false.
      call check(error, baseline_left_behind(res) == 2, 'an effect not refitted counted')
      if (allocated(error)) return
      ! deviance 100 ln(1.5) + 1000 ln(0.95) = -10.8, but a sum of 2.45 against 2.0
      res%effects(2)%per_constants = [1.5_dp, 0.95_dp, 1.0_dp]
      call check(error, baseline_left_behind(res) == 0, 'a higher objective counted as better')
      if (allocated(error)) return
      res%effects(2)%per_constants = [1.0_dp, 0.995_dp, 1.0_dp]
      call check(error, baseline_left_behind(res) == 0, 'a deviance within the BIC margin counted')
      if (allocated(error)) return
      res%effects(2)%per_constants = [1.0_dp, 0.98_dp, 1.0_dp]
      res%global = .true.
      res%f0_global = 1.97_dp
      res%per_test_global = [0.99_dp, 0.98_dp, 5.0_dp]
      call check(error, baseline_left_behind(res) == 0, 'left behind by constants no lower than '// &
                 'the global stage''s baseline')
   end subroutine test_left_behind

   !> A diagnosis whose fit tests (npts points, baseline sums of squares f0) and held-out
   !> tests both lie below their floors
   subroutine below_floors_case(npts, f0, ctx, res)
      integer, intent(in) :: npts(:)
      real(dp), intent(in) :: f0(:)
      type(diagnose_context), intent(out) :: ctx
      type(diagnose_result), intent(out) :: res
      integer :: i
      ctx%opts%confirm_shrink = 0.5_dp
      ctx%ifit = [(i, i=1, size(npts))]
      res%npts = npts
      res%per_test0 = f0
      res%m = sum(npts)
      res%f0 = sum(f0)
      res%gap_fit = 0.1_dp
      res%floor_fit = 0.2_dp
      res%gap_held = 0.05_dp
      res%floor_held = 0.1_dp
   end subroutine below_floors_case

   !> The leading n_refit effects are refitted and those the screening cannot tell from them
   !> (predicted BIC within 10 % or bic_margin of the last, or a predicted fall within
   !> rival_share of the largest), not one more
   subroutine test_near_ties(error)
      type(error_type), allocatable, intent(out) :: error
      type(diagnose_result) :: res
      allocate (res%effects(5))
      res%effects%pred_dbic = [-1081.0_dp, -1066.0_dp, -1007.0_dp, -984.0_dp, -152.0_dp]
      res%effects%pred_drop = [60.0_dp, 59.0_dp, 56.0_dp, 30.0_dp, 8.0_dp]
      call check(error, n_leading(res, 3) == 4, 'a near tie at -984 against -1007 not refitted')
      if (allocated(error)) return
      res%effects(4)%pred_dbic = -500.0_dp
      call check(error, n_leading(res, 3) == 3, 'an effect far behind refitted')
      if (allocated(error)) return
      ! A second back stress of 1.37 ksi (ratcheting test held out): 4th at -606.1 against
      ! -690.5, outside 10 %, but its predicted fall is 87 % of the leader's
      res%effects%pred_dbic = [-757.4_dp, -740.3_dp, -690.5_dp, -606.1_dp, -124.9_dp]
      res%effects%pred_drop = [1.124_dp, 1.119_dp, 1.071_dp, 0.974_dp, 0.156_dp]
      call check(error, n_leading(res, 3) == 4, 'a predicted fall at 87 % of the leader''s not refitted')
      if (allocated(error)) return
      res%effects(4)%pred_drop = 0.85_dp
      call check(error, n_leading(res, 3) == 3, 'a predicted fall at 76 % of the leader''s refitted')
      if (allocated(error)) return
      res%effects%pred_dbic = [-8.0_dp, -7.0_dp, -6.0_dp, -5.0_dp, -4.0_dp]
      res%effects%pred_drop = 1.0_dp
      call check(error, n_leading(res, 3) == 3, 'insignificant predictions refitted beyond n_refit')
   end subroutine test_near_ties

   !> A leader with parameters per test is checked against the simpler effects not yet
   !> refitted that the screening found significant or whose predicted fall is at least
   !> rival_share of the leader's (thesis tests, ratcheting held out, a temperature offset of
   !> -22.4 K: scatter led, the temperature offset screened 8th at +14.9 with a fall of 0.88)
   subroutine test_simpler_rivals(error)
      type(error_type), allocatable, intent(out) :: error
      type(diagnose_result) :: res
      logical :: s(5)
      allocate (res%effects(5))
      ! softening, scatter (leads), lag, temperature, drift
      res%effects%q = [2, 4, 1, 2, 2]
      res%effects%refitted = [.true., .true., .false., .false., .false.]
      res%effects%pred_dbic = [-221.0_dp, -118.6_dp, -21.8_dp, 14.9_dp, 14.9_dp]
      res%effects%pred_drop = [2.545_dp, 0.553_dp, 0.065_dp, 0.878_dp, 0.024_dp]
      res%leading = 2
      s = simpler_rivals(res, .true.)
      call check(error, all(s .eqv. [.false., .false., .true., .true., .false.]), &
                 'simpler rivals: a significant one or a fall as large as the leader''s')
      if (allocated(error)) return
      call check(error, .not. any(simpler_rivals(res, .false.)), 'rivals of a leader without per-test parameters')
      if (allocated(error)) return
      ! At rival_share of the leader's fall exactly it is tried, below it not
      res%effects(4)%pred_drop = 0.8_dp*0.553_dp
      s = simpler_rivals(res, .true.)
      call check(error, s(4), 'a fall at rival_share of the leader''s not tried')
      if (allocated(error)) return
      res%effects(4)%pred_drop = 0.79_dp*0.553_dp
      s = simpler_rivals(res, .true.)
      call check(error, .not. s(4), 'a fall below rival_share of the leader''s tried')
      if (allocated(error)) return
      ! Not simpler: as many parameters as the leader
      res%effects(4)%pred_drop = 0.878_dp
      res%effects(4)%q = 4
      s = simpler_rivals(res, .true.)
      call check(error, .not. s(4), 'an effect as free as the leader tried as simpler')
      if (allocated(error)) return
      res%leading = 0
      call check(error, .not. any(simpler_rivals(res, .true.)), 'rivals without a leader')
   end subroutine test_simpler_rivals

   !> An effect is below what the diagnosis resolves only where every parameter with a low
   !> end has a bounded 95 % interval inside resolved_share (a quarter) of it: a temperature
   !> offset of -0.65 K [-0.92, -0.35] (low end 5 K) is; one of -5.10 K [-5.49, -4.65] at the
   !> low end is not, nor Alloy 617 specimen 435's lag of 88 ms [77, 99] (low end 0.1 s)
   subroutine test_below_resolved(error)
      type(error_type), allocatable, intent(out) :: error
      call check(error, resolved_share == 0.25_dp, 'resolved_share is not a quarter')
      if (allocated(error)) return
      call check(error, below_resolved([-0.92_dp], [-0.35_dp], [.false.], [5.0_dp]), &
                 'an offset of -0.65 K [-0.92, -0.35] resolved against a low end of 5 K')
      if (allocated(error)) return
      call check(error, .not. below_resolved([-5.49_dp], [-4.65_dp], [.false.], [5.0_dp]), &
                 'an offset at the low end taken as unresolved')
      if (allocated(error)) return
      call check(error, .not. below_resolved([-1.3_dp], [-0.2_dp], [.false.], [5.0_dp]), &
                 'an interval beyond a quarter of the low end taken as unresolved')
      if (allocated(error)) return
      call check(error, .not. below_resolved([0.0767_dp], [0.0989_dp], [.false.], [0.1_dp]), &
                 'a lag of 88 ms [77, 99] taken as unresolved')
      if (allocated(error)) return
      call check(error, .not. below_resolved([-0.9_dp], [-0.3_dp], [.true.], [5.0_dp]), &
                 'an interval the data do not bound taken as unresolved')
      if (allocated(error)) return
      ! Two parameters (R0 or dD0 2 % of a peak of 20 MPa): unresolved only if both are
      call check(error, below_resolved([-0.05_dp, 0.0_dp], [0.05_dp, 0.08_dp], [.false., .false.], &
                                       [0.4_dp, 0.4_dp]), 'R0 and dD0 both within a quarter of the low end resolved')
      if (allocated(error)) return
      call check(error, .not. below_resolved([-0.05_dp, 0.0_dp], [0.05_dp, 0.3_dp], [.false., .false.], &
                                              [0.4_dp, 0.4_dp]), 'dD0 beyond a quarter of the low end taken as unresolved')
      if (allocated(error)) return
      ! A parameter without a low end (softening's b) is not judged; none at all: resolved
      call check(error, below_resolved([0.01_dp, 10.0_dp], [0.012_dp, 1.0e4_dp], [.false., .true.], [0.05_dp, 0.0_dp]), &
                 'a softening of 0.011 resolved against a low end of 0.05')
      if (allocated(error)) return
      call check(error, .not. below_resolved([0.001_dp], [0.002_dp], [.false.], [0.0_dp]), &
                 'an effect without a low end taken as unresolved')
   end subroutine test_below_resolved

   !> The separating step: two refits that predict alike give D = 0 on every candidate; a
   !> compliance of 0.2 against none is told apart (D far above 10) by the best candidate,
   !> which the verdict names. The same between the end points of a leader that leave its
   !> held-out prediction open: none told apart where they are one point, the best named
   !> where they differ by a compliance of 0.2; not computed where the shares part by less
   !> than open_spread
   subroutine test_separate(error)
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: e
      type(diagnose_context) :: ctx
      type(diagnose_result) :: res
      call separation_baseline('diag-separate.nml', ctx, res, e)
      call check(error, .not. allocated(e), 'baseline failed')
      if (allocated(error)) return
      allocate (res%effects(2))
      res%effects%k = 1
      res%effects(1)%name = 'compliance'
      res%effects(2)%name = 'compliance'
      res%effects(1)%p_all = [0.0_dp]
      res%effects(2)%p_all = [0.0_dp]
      res%effects(1)%c = res%c
      res%effects(2)%c = res%c
      res%alike = [1, 2]
      res%verdict = 'v'
      call separate(ctx, res)
      call check(error, size(res%seps) == 1, 'one pair expected')
      if (allocated(error)) return
      call check(error, all(res%seps(1)%d == 0.0_dp) .and. res%verdict == 'v', &
                 'identical refits told apart')
      if (allocated(error)) return
      res%effects(2)%p_all = [0.2_dp]
      call separate(ctx, res)
      associate (sp => res%seps(1))
         call check(error, sp%d(sp%best) > 100.0_dp .and. sp%d(sp%best) == maxval(sp%d) .and. &
                    index(res%verdict, trim(sp%names(sp%best))) > 0, 'compliance 0.2 not told apart: D '// &
                    real_str(sp%d(sp%best), 'es10.3')//'; '//res%verdict)
      end associate
      if (allocated(error)) return
      ! A leader whose end points alike on the fit tests carry 55 % and 90 % of the held-out gap
      deallocate (res%alike)
      res%leading = 1
      res%effects(1)%n_alike = 2
      res%effects(1)%shrink_alike_lo = 0.55_dp
      res%effects(1)%shrink_alike_hi = 0.90_dp
      res%effects(1)%c_open = reshape([res%c, res%c], [size(res%c), 2])
      res%effects(1)%p_open = reshape([0.0_dp, 0.0_dp], [1, 2])
      res%verdict = 'v'
      call separate(ctx, res)
      call check(error, res%pin%best > 0 .and. all(res%pin%d == 0.0_dp) .and. &
                 res%verdict(2:) == '; none of the candidate tests would tell those end points apart '// &
                 '(expected chi-square difference 0.00E+00 between the two that carry 55.0 and 90.0 %)', &
                 'one point told apart from itself: '//res%verdict)
      if (allocated(error)) return
      res%effects(1)%p_open(1, 2) = 0.2_dp
      res%verdict = 'v'
      call separate(ctx, res)
      associate (sp => res%pin)
         call check(error, sp%a == 1 .and. sp%b == 1 .and. sp%d(sp%best) > separating_d .and. &
                    sp%d(sp%best) == maxval(sp%d) .and. index(res%verdict, '; a '//trim(sp%names(sp%best))// &
                    ' would tell those end points apart') > 0, 'end points a compliance of 0.2 apart not told '// &
                    'apart: '//res%verdict)
      end associate
      if (allocated(error)) return
      res%effects(1)%shrink_alike_hi = 0.55_dp + 0.9_dp*open_spread
      res%verdict = 'v'
      call separate(ctx, res)
      call check(error, res%pin%best == 0 .and. res%verdict == 'v', 'shares closer than open_spread: '//res%verdict)
   end subroutine test_separate

   !> The saturating softening: at p = 0 the plain flow, at p >> 1/b the flow of the drag
   !> D(1 - a); its Jacobian columns in D and p against central differences half-way to
   !> saturation, for softening and hardening
   subroutine test_softening(error)
      type(error_type), allocatable, intent(out) :: error
      type(miller_model) :: model
      type(test_effects) :: eff, none
      real(dp) :: y(n_extended), f(n_extended), g(n_extended), fp(n_extended), fm(n_extended)
      real(dp) :: jac(n_extended, n_extended), yp(n_extended), ym(n_extended), fd, h, worst
      real(dp), parameter :: sigma = 25.0_dp
      integer :: j, sgn
      character(len=120) :: buf
      call thesis_model(model)
      eff%soften = 0.15_dp
      eff%soften_rate = 200.0_dp
      y = [1.0e-3_dp, 1.0_dp, model%d0, 0.0_dp, 0.0_dp]
      call extended_rates(model, eff, sigma, y, f)
      call extended_rates(model, none, sigma, y, g)
      call check(error, all(f == g), 'softening acts at p = 0')
      if (allocated(error)) return
      y(4) = 1.0_dp
      call extended_rates(model, eff, sigma, y, f)
      y(3) = model%d0*(1.0_dp - eff%soften)
      call extended_rates(model, none, sigma, y, g)
      write (buf, '(a,2es12.4)') 'saturated flow rate against the drag D(1 - a): ', f(1), g(1)
      call check(error, abs(f(1) - g(1)) <= 1.0e-12_dp*abs(g(1)) .and. f(1) > 1.0e-3_dp*g(1), trim(buf))
      if (allocated(error)) return
      worst = 0.0_dp
      do sgn = -1, 1, 2
         eff%soften = sgn*0.15_dp
         y = [1.0e-3_dp, 1.0_dp, model%d0, 0.005_dp, 0.2_dp]
         call extended_rates(model, eff, sigma, y, f, -model%youngs, jac)
         do j = 3, 4
            h = 1.0e-6_dp*abs(y(j))
            yp = y
            ym = y
            yp(j) = y(j) + h
            ym(j) = y(j) - h
            call extended_rates(model, eff, sigma, yp, fp)
            call extended_rates(model, eff, sigma, ym, fm)
            fd = maxval(abs(jac(:, j) - (fp - fm)/(2.0_dp*h)))/maxval(abs((fp - fm)/(2.0_dp*h)))
            worst = max(worst, fd)
         end do
      end do
      write (buf, '(a,es10.2)') 'softening Jacobian columns D, p: worst |jac - difference|/max ', worst
      call check(error, worst <= 1.0e-6_dp, trim(buf))
   end subroutine test_softening

   !> A softening that saturates within the first loading (a = 0.1, b = 1000) and a drag
   !> offset of the initial state (-0.1 D0) predict the later cycles alike; the separating
   !> step finds a candidate that tells them apart (D above 10, a fresh first loading) and
   !> the verdict names it
   subroutine test_separate_softening(error)
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: e
      type(diagnose_context) :: ctx
      type(diagnose_result) :: res
      type(miller_model) :: model
      call separation_baseline('diag-separate-soft.nml', ctx, res, e)
      select type (m => ctx%prob%cfg%model)
      type is (miller_model)
         model = m
      end select
      if (.not. allocated(e)) call model_setup(model, e)
      call check(error, .not. allocated(e), 'baseline failed')
      if (allocated(error)) return
      allocate (res%effects(2))
      res%effects(1)%k = 7
      res%effects(1)%name = 'softening'
      res%effects(1)%p_all = [0.1_dp, 1000.0_dp]
      res%effects(2)%k = 5
      res%effects(2)%name = 'initial'
      res%effects(2)%p_all = [0.0_dp, -0.1_dp*model%d0]
      res%effects(1)%c = res%c
      res%effects(2)%c = res%c
      res%alike = [1, 2]
      res%verdict = 'v'
      call separate(ctx, res)
      associate (sp => res%seps(1))
         call check(error, sp%d(sp%best) > 10.0_dp .and. &
                    index(res%verdict, 'would tell softening from initial') > 0 .and. &
                    index(res%verdict, trim(sp%names(sp%best))) > 0, 'softening and initial not told '// &
                    'apart: D '//real_str(sp%d(sp%best), 'es10.3')//'; '//res%verdict)
      end associate
   end subroutine test_separate_softening

   !> The baseline of the separating-step tests: B fitted to relaxation test a, b held out
   subroutine separation_baseline(deck, ctx, res, e)
      character(len=*), intent(in) :: deck
      type(diagnose_context), intent(out) :: ctx
      type(diagnose_result), intent(out) :: res
      type(uerror), allocatable, intent(out) :: e
      type(run_config) :: cfg
      type(diagnose_options) :: opts
      call write_relaxation_data('a.txt', 1.0_dp, e)
      if (.not. allocated(e)) call read_config(write_text(deck, [character(len=100) :: &
         model_groups, "&fit fitted = 'B', method = 'lm' /", "&diagnose holdout = 'b' /", &
         "&test name = 'a', history = 'relaxation', data_file = 'a.txt' /", &
         "&test name = 'b', history = 'relaxation', data_file = 'a.txt' /"]), cfg, e)
      if (.not. allocated(e)) call diagnose_options_of(cfg, opts, e)
      if (.not. allocated(e)) call diagnose_baseline(cfg, opts, ctx, res, e)
   end subroutine separation_baseline

   !> The stage with every test fitted together runs when nothing is confirmed, the held-out
   !> tests have a structured gap and the fit tests cannot say which effect it is: no
   !> structured gap, or one that no significant effect explains, or one an effect takes to
   !> its floor without carrying to the held-out tests (its form left open, whatever the
   !> held-out gap); not when a significant effect explains only part of the fit tests' gap,
   !> nor when one is confirmed, unless its confirmation is a prediction from a baseline that
   !> ran to a search bound while the fit tests have no structured gap
   !> A leader whose prediction carries part of the held-out gap keeps its verdict, and every
   !> test fitted together adds how much of every gap the same effect closes (the numbers of
   !> a softening of 0.17 with the relaxation test held out)
   subroutine test_partial_carry(error)
      type(error_type), allocatable, intent(out) :: error
      type(diagnose_result) :: res, jres
      character(len=*), parameter :: before = 'softening partly explains the gap: BIC -582.9'
      res%held = [.false., .true., .false.]
      res%gap_fit = 0.4_dp
      res%floor_fit = 0.2_dp
      res%gap_held = 1.0_dp
      res%floor_held = 0.2_dp
      allocate (res%effects(1))
      res%effects(1)%name = 'softening'
      res%effects(1)%confirmed = .true.
      res%effects(1)%shrink_fit = 1.0_dp
      res%effects(1)%shrink_held = 0.546_dp
      res%leading = 1
      res%verdict = before
      call check(error, joint_wanted(res, .false.), 'a prediction that carries 55 % goes on to every test fitted')
      if (allocated(error)) return
      jres%held = [.false., .false., .false.]
      jres%gap_fit = 1.2_dp
      jres%floor_fit = 0.2_dp
      jres%effects = res%effects
      jres%effects(1)%shrink_fit = 1.0_dp
      jres%effects(1)%dbic = -676.3_dp
      jres%leading = 1
      jres%verdict = 'softening explains the gap'
      call joint_verdict(res, jres)
      call check(error, index(res%verdict, before) == 1, 'the prediction''s verdict stays first: '//res%verdict)
      if (allocated(error)) return
      call check(error, index(res%verdict, 'fitted to every test together, softening removes 100.0 % of their '// &
                 'structured gap (BIC -676.3): it can explain every test, but with the constants the fit tests '// &
                 'alone give it, its parameters carry 54.6 % of the held-out gap') > 0, res%verdict)
      if (allocated(error)) return
      ! The prediction's leader stays the one named
      res%effects(1)%k = 7
      jres%effects(1)%k = 7
      res%joint = jres
      call check(error, .not. joint_decides(res) .and. named_effect(res) == 7, 'the prediction''s leader is named')
      if (allocated(error)) return
      deallocate (res%joint)
      ! Every test fitted together at the noise level without an effect
      res%verdict = before
      jres%leading = 0
      jres%gap_fit = 0.1_dp
      call joint_verdict(res, jres)
      call check(error, index(res%verdict, 'the model without an effect is at the noise level') > 0, res%verdict)
      if (allocated(error)) return
      jres%leading = 1
      jres%gap_fit = 1.2_dp
      ! Another effect leads when every test is fitted: its verdict is added as it is
      res%verdict = before
      jres%effects(1)%name = 'lag'
      jres%verdict = 'lag explains the gap'
      call joint_verdict(res, jres)
      call check(error, res%verdict == before//'; with the held-out tests fitted too, lag explains the gap', &
                 res%verdict)
   end subroutine test_partial_carry

   !> A per-test leader whose held-out values, fitted with the fit tests' constants, meet part
   !> of the held-out gap goes on to every test fitted together; where the same effect there
   !> removes most of the held-out gap at constants the fit tests allow (their deviance within
   !> the 95 % region of the parameters the tests share), the verdict says it explains the
   !> gap and that the fit tests leave those constants open; beyond the region it stays
   !> "partly" (the numbers of a drift with the LCF test held out)
   subroutine test_held_agreement(error)
      type(error_type), allocatable, intent(out) :: error
      type(diagnose_result) :: res, jres
      character(len=*), parameter :: before = 'drift partly explains the gap: BIC -625.2'
      res%held = [.true., .false., .false.]
      res%npts = [1000, 1202, 1202]
      res%c = [1.0_dp, 2.0_dp, 3.0_dp, 4.0_dp, 5.0_dp, 6.0_dp, 7.0_dp]
      res%gap_fit = 0.159_dp
      res%floor_fit = 0.075_dp
      ! held-out objective 10.57: noise 0.36, and 0.17 from the constants' own uncertainty
      res%noise_held = 0.53_dp
      res%pred_held = 0.17_dp
      res%gap_held = 10.04_dp
      res%gap_held_noise = 10.21_dp
      res%floor_held = 0.657_dp
      allocate (res%effects(1))
      res%effects(1)%name = 'drift'
      res%effects(1)%confirmed = .true.
      res%effects(1)%held_fitted = .true.
      res%effects(1)%shrink_fit = 1.0_dp
      res%effects(1)%shrink_held = 0.723_dp
      res%effects(1)%dbic = -625.2_dp
      res%effects(1)%worse = [.false., .false., .false.]
      res%alike = [1]
      res%effects(1)%per_test_after = [3.316_dp, 0.2549_dp, 0.2454_dp]
      res%effects(1)%p_test = [2, 3]
      res%leading = 1
      res%verdict = before
      call check(error, joint_wanted(res, .false.), 'held-out values meeting 72 % go on to every test fitted')
      if (allocated(error)) return
      jres%held = [.false., .false., .false.]
      jres%gap_fit = 0.88_dp
      jres%floor_fit = 0.144_dp
      jres%effects = res%effects
      jres%effects(1)%held_fitted = .false.
      jres%effects(1)%shrink_fit = 0.973_dp
      jres%effects(1)%dbic = -1724.2_dp
      ! the fit tests each 0.4 % above their own fit: deviance 2*1202*ln(1.004) = 9.6
      jres%effects(1)%per_test_after = [0.38_dp, 1.004_dp*0.2549_dp, 1.004_dp*0.2454_dp]
      jres%leading = 1
      jres%verdict = 'drift explains the gap'
      call joint_verdict(res, jres)
      call check(error, index(res%verdict, 'drift explains the gap: BIC -625.2') == 1, res%verdict)
      if (allocated(error)) return
      call check(error, index(res%verdict, 'and 99.8 % of the held-out tests'' gap against their noise, at '// &
                 'constants the fit tests allow (their deviance up 9.6 from their own fit, within the 14.1 of a '// &
                 '95 % region of the 7 parameters the tests share): it explains every test, and the fit tests '// &
                 'leave open what the held-out tests need: with the constants they alone give it, its values '// &
                 'fitted to the held-out tests meet 72.3 % of their gap') > 0, res%verdict)
      if (allocated(error)) return
      ! Another effect explains every test as well there: the headline stays "partly"
      res%verdict = before
      jres%alike = [1, 2]
      call joint_verdict(res, jres)
      call check(error, index(res%verdict, before) == 1, 'with an alike effect: '//res%verdict)
      if (allocated(error)) return
      deallocate (jres%alike)
      ! The fit tests each 1 % worse: deviance 23.9, beyond the region; the verdict stays "partly"
      jres%effects(1)%per_test_after = [0.38_dp, 1.01_dp*0.2549_dp, 1.01_dp*0.2454_dp]
      res%verdict = before
      call joint_verdict(res, jres)
      call check(error, index(res%verdict, before) == 1 .and. index(res%verdict, 'at constants the fit tests '// &
                 'do not allow (their deviance up 23.9 from their own fit, beyond the 14.1') > 0 .and. &
                 index(res%verdict, 'it can explain every test, but with the constants the fit tests alone '// &
                 'give it') > 0, res%verdict)
   end subroutine test_held_agreement

   !> The specimen's -2 log-likelihood in the covariance s diag(nv) + Jc C Jc', minimised over
   !> the noise scale s: against the whole matrix factorised and solved at each s; without C,
   !> m ln(|x|**2/m) + m; and where the residual's structure lies along the constants'
   !> directions far beyond what C allows, an effect removing it keeps nearly the whole of
   !> its deviance (the constants cannot take it up for free). The noise scale at the minimum,
   !> and a signal's chi-square in that covariance (what the power is computed from), against
   !> the whole matrix solved
   subroutine test_specimen_quad(error)
      type(error_type), allocatable, intent(out) :: error
      type(specimen_result) :: sr
      real(dp), allocatable :: r(:), s(:, :), x(:, :), jc(:, :), cov(:, :), re(:), d(:)
      real(dp) :: dev, direct, t, best, logdet, old, new, sc, tbest, lam
      integer :: i, j, m, info, it
      m = 40
      allocate (r(m), sr%nv(m), jc(m, 3))
      do i = 1, m
         r(i) = sin(0.7_dp*i) + 0.1_dp*i/m
         sr%nv(i) = 0.5_dp + 0.01_dp*i
         do j = 1, 3
            jc(i, j) = cos(0.3_dp*i*j) + 0.05_dp*j
         end do
      end do
      allocate (sr%w(m, 0), sr%sig2(0))
      dev = specimen_deviance(sr, r)
      direct = m*log(sum(r**2/sr%nv)/m) + m
      call check(error, abs(dev - direct) <= 1.0e-9_dp*abs(direct), 'without the constants'' covariance: '// &
                 real_str(dev, 'es22.14')//' against '//real_str(direct, 'es22.14'))
      if (allocated(error)) return
      cov = reshape([1.0_dp, 0.2_dp, -0.1_dp, 0.2_dp, 0.5_dp, 0.05_dp, -0.1_dp, 0.05_dp, 0.3_dp], [3, 3])
      do i = 1, 2
         ! A covariance of full rank and one of rank 1 (a pseudo-inverse's)
         if (i == 2) cov = spread([1.0_dp, -2.0_dp, 0.5_dp], 2, 3)*spread([1.0_dp, -2.0_dp, 0.5_dp], 1, 3)
         call constants_directions(sr, jc, cov)
         dev = specimen_deviance(sr, r)
         ! The whole matrix at s on a fine grid of ln s, then the least
         best = huge(1.0_dp)
         do it = -4000, 4000
            t = 1.0e-3_dp*it
            s = matmul(matmul(jc, cov), transpose(jc))
            do j = 1, m
               s(j, j) = s(j, j) + exp(t)*sr%nv(j)
            end do
            call logdet_spd(s, logdet, info)
            x = reshape(r, [m, 1])
            call solve_dense(s, x, info)
            if (logdet - sum(log(sr%nv)) + dot_product(r, x(:, 1)) < best) tbest = t
            best = min(best, logdet - sum(log(sr%nv)) + dot_product(r, x(:, 1)))
         end do
         call check(error, abs(dev - best) <= 1.0e-5_dp*abs(best), 'profiled '//real_str(dev, 'es22.14')// &
                    ' against the whole matrix '//real_str(best, 'es22.14'))
         if (allocated(error)) return
         ! The scale at the minimum, and a signal's chi-square there: d' S^-1 d solved whole
         call profiled_deviance(sr, r, dev, sc)
         call check(error, abs(log(sc) - tbest) <= 2.0e-3_dp, 'the noise scale at the minimum: ln s '// &
                    real_str(log(sc), 'f0.5')//' against the grid''s '//real_str(tbest, 'f0.5'))
         if (allocated(error)) return
         d = 0.2_dp*cos(1.3_dp*[(real(j, dp), j=1, m)]) + 0.5_dp*jc(:, 2)
         s = matmul(matmul(jc, cov), transpose(jc))
         do j = 1, m
            s(j, j) = s(j, j) + sc*sr%nv(j)
         end do
         x = reshape(d, [m, 1])
         call solve_dense(s, x, info)
         lam = specimen_noncentrality(sr, d, sc)
         call check(error, abs(lam - dot_product(d, x(:, 1))) <= 1.0e-9_dp*lam, 'chi-square of a signal '// &
                    real_str(lam, 'es22.14')//' against the whole matrix '//real_str(dot_product(d, x(:, 1)), 'es22.14'))
         if (allocated(error)) return
      end do
      ! Structure along the constants' directions of 1e4 times what C allows there: an effect
      ! that removes it lowers the deviance nearly as with the constants held exact
      cov = 1.0e-4_dp*reshape([1.0_dp, 0.2_dp, -0.1_dp, 0.2_dp, 0.5_dp, 0.05_dp, -0.1_dp, 0.05_dp, 0.3_dp], [3, 3])
      call constants_directions(sr, jc, cov)
      re = 0.3_dp*sin(2.1_dp*[(real(i, dp), i=1, m)])
      r = re + 3.0_dp*jc(:, 1)
      new = specimen_deviance(sr, re) - specimen_deviance(sr, r)
      old = m*log(sum(re**2/sr%nv)/sum(r**2/sr%nv))
      call check(error, new < 0.9_dp*old .and. new < 0.0_dp, 'structure beyond the constants'' uncertainty: '// &
                 real_str(new, 'es10.3')//' against '//real_str(old, 'es10.3')//' with the constants exact')
   end subroutine test_specimen_quad

   subroutine test_joint_rule(error)
      type(error_type), allocatable, intent(out) :: error
      type(diagnose_result) :: res
      res%gap_fit = 0.093_dp
      res%floor_fit = 0.090_dp
      res%gap_held_noise = 439.0_dp
      res%floor_held_noise = 154.0_dp
      allocate (res%effects(2))
      res%effects%refitted = .true.
      call check(error, joint_reason(res, .false.) == joint_held_only .and. joint_wanted(res, .false.), &
                 'a structured gap that no significant effect explains')
      if (allocated(error)) return
      call check(error, .not. joint_wanted(res, .true.), 'the joint diagnosis does not go on')
      if (allocated(error)) return
      res%gap_fit = 1.0_dp
      call check(error, joint_wanted(res, .false.), 'a larger structured gap that no significant effect explains')
      if (allocated(error)) return
      res%effects(2)%significant = .true.
      res%effects(2)%shrink_fit = 0.5_dp
      ! (the Alloy 617 tests with E12 and J2 held out: significant effects, none confirmed, and
      ! the held-out tests with a gap of their own had ended without every test fitted)
      call check(error, joint_reason(res, .false.) == joint_not_carried, &
                 'a significant effect explains part of the fit gap and carries to no held-out test')
      if (allocated(error)) return
      res%gap_held_noise = 100.0_dp
      call check(error, .not. joint_wanted(res, .false.), &
                 'a significant effect explains part of the fit gap, the held-out tests at their noise')
      if (allocated(error)) return
      res%gap_held_noise = 439.0_dp
      res%effects(2)%shrink_fit = 0.99_dp
      call check(error, joint_reason(res, .false.) == joint_form_open, 'an effect takes the fit gap to its floor, not confirmed')
      if (allocated(error)) return
      res%effects(2)%plausible = .false.
      call check(error, joint_reason(res, .false.) == joint_not_carried, &
                 'that effect at an implausible magnitude, carried to no held-out test')
      if (allocated(error)) return
      res%effects(2)%plausible = .true.
      res%leading = 2
      res%effects(2)%confirmed = .true.
      call check(error, .not. joint_wanted(res, .false.), 'an effect is confirmed')
      if (allocated(error)) return
      ! Confirmed by its BIC alone, both sets below their floors: every test fitted decides
      res%held = [.true., .false., .false.]
      res%gap_fit = 0.0_dp
      res%gap_held = 0.0_dp
      res%floor_held = 2645.0_dp
      call check(error, joint_reason(res, .false.) == joint_bic_only, 'an effect leads by BIC alone, both sets below their floors')
      if (allocated(error)) return
      ! The fit tests with a structured gap that the leader mostly leaves, the held-out quiet
      res%gap_fit = 1.0_dp
      res%effects(2)%shrink_fit = 0.11_dp
      call check(error, joint_reason(res, .false.) == joint_bic_only, 'an effect leads by BIC alone, most of the fit gap left')
      if (allocated(error)) return
      res%effects(2)%shrink_fit = 0.95_dp
      call check(error, .not. joint_wanted(res, .false.), 'the leader takes most of the fit tests'' gap')
      if (allocated(error)) return
      res%gap_fit = 0.0_dp
      res%effects(2)%k = 5
      call check(error, named_effect(res) == 5, 'no joint stage yet: the leading effect is named')
      if (allocated(error)) return
      allocate (res%joint)
      res%joint%gap_fit = 3.0_dp
      res%joint%floor_fit = 0.1_dp
      call check(error, .not. joint_decides(res) .and. named_effect(res) == 5, &
                 'a joint stage that confirms nothing in a structured gap leaves the leading effect named')
      if (allocated(error)) return
      res%joint%effects = res%effects
      res%joint%effects(1)%k = 7
      res%joint%leading = 1
      call check(error, joint_decides(res) .and. named_effect(res) == 7, 'the joint stage''s effect is named')
      if (allocated(error)) return
      res%joint%leading = 0
      res%joint%gap_fit = 0.05_dp
      call check(error, joint_decides(res) .and. named_effect(res) == 0, &
                 'every test fitted together at the noise level: no effect is named')
      if (allocated(error)) return
      deallocate (res%joint)
      res%gap_held = 10.0_dp
      res%floor_held = 1.0_dp
      res%effects(2)%shrink_held = 0.9_dp
      call check(error, .not. joint_wanted(res, .false.), 'the held-out tests confirm it')
      if (allocated(error)) return
      ! Its prediction carries only part of the held-out gap (a softening fitted to the LCF and
      ! ratcheting tests carried 55 % to the relaxation test): every test fitted says whether
      ! the effect can close it all
      res%effects(2)%shrink_held = 0.55_dp
      call check(error, joint_reason(res, .false.) == joint_partial, 'the prediction carries part of the held-out gap')
      if (allocated(error)) return
      res%gap_held = 3.0_dp
      res%effects(2)%shrink_held = 0.75_dp
      call check(error, .not. joint_wanted(res, .false.), 'the rest of the held-out gap below its floor')
      if (allocated(error)) return
      res%gap_held = 10.0_dp
      res%effects(2)%shrink_held = 0.9_dp
      ! ... but the baseline ran away (a constant at a search bound): the prediction that
      ! confirms it rests on constants the fit tests leave loose
      res%c_bound = [1, 0]
      call check(error, joint_reason(res, .false.) == joint_loose, 'a prediction from a baseline at a bound confirms it')
      if (allocated(error)) return
      res%gap_fit = 1.0_dp
      call check(error, .not. joint_wanted(res, .false.), &
                 'a baseline at a bound, the leader takes most of the fit tests'' structured gap')
      if (allocated(error)) return
      res%gap_fit = 0.0_dp
      deallocate (res%c_bound)
      res%leading = 0
      res%effects(2)%confirmed = .false.
      res%effects(2)%significant = .false.
      res%gap_held_noise = 100.0_dp
      call check(error, .not. joint_wanted(res, .false.), 'nothing significant, the held-out tests at their noise')
   end subroutine test_joint_rule

   !> The candidates the screening ranked lower are refitted (and the global starts run) while
   !> the fit tests have a structured gap that no significant refit takes to its floor: also
   !> when a confirmed effect leads but leaves part of it (a 24.5 K temperature offset,
   !> screened 7th, had lost to a scatter that removed half of the fit tests' gap); and when
   !> only the held-out tests show a gap
   subroutine test_gap_left_rule(error)
      type(error_type), allocatable, intent(out) :: error
      type(diagnose_result) :: res
      res%gap_fit = 0.172_dp
      res%floor_fit = 0.080_dp
      allocate (res%effects(3))
      res%effects%refitted = [.true., .true., .false.]
      res%effects%significant = [.true., .true., .false.]
      res%effects%shrink_fit = [0.36_dp, 0.505_dp, 0.0_dp]
      res%effects(2)%confirmed = .true.
      res%leading = 2
      call check(error, fit_gap_left(res), 'the leader removes half of the fit tests'' gap')
      if (allocated(error)) return
      res%effects(3)%shrink_fit = 0.9_dp
      call check(error, fit_gap_left(res), 'an effect not refitted does not count')
      if (allocated(error)) return
      res%effects(3)%refitted = .true.
      call check(error, fit_gap_left(res), 'nor one that is not significant')
      if (allocated(error)) return
      res%effects(3)%significant = .true.
      call check(error, .not. fit_gap_left(res), 'a significant refit takes the gap to its floor')
      if (allocated(error)) return
      call check(error, .not. rest_wanted(res), 'the leader is confirmed and another takes the gap')
      if (allocated(error)) return
      res%effects(3)%significant = .false.
      call check(error, rest_wanted(res), 'the lower-ranked are refitted while the gap is left')
      if (allocated(error)) return
      res%gap_fit = 0.07_dp
      call check(error, .not. fit_gap_left(res), 'no structured gap on the fit tests')
      if (allocated(error)) return
      ! The fit tests at their noise: the held-out tests decide whether all are refitted
      allocate (res%held(3))
      res%held = [.true., .false., .false.]
      res%gap_held = 441.0_dp
      res%floor_held = 150.0_dp
      call check(error, rest_wanted(res), 'only the held-out tests show a gap')
      if (allocated(error)) return
      res%gap_held = 100.0_dp
      call check(error, .not. rest_wanted(res), 'neither set shows a gap')
   end subroutine test_gap_left_rule

   !> Constructed results of two refitted effects on three tests, the middle one held out,
   !> with the structured gaps and floors of the fit and held-out tests
   subroutine held_out_middle(res, gap_fit, floor_fit, gap_held, floor_held)
      type(diagnose_result), intent(out) :: res
      real(dp), intent(in) :: gap_fit, floor_fit, gap_held, floor_held
      allocate (res%effects(2))
      res%held = [.false., .true., .false.]
      res%gap_fit = gap_fit
      res%floor_fit = floor_fit
      res%gap_held = gap_held
      res%floor_held = floor_held
      res%effects%refitted = .true.
   end subroutine held_out_middle

   !> A leader confirmed on the held-out tests only by its own parameters fitted to them, while
   !> it explains little of the fit tests (a drift at 12.6 % of their gap, or with the fit tests
   !> at their noise level), sends the diagnosis on to fit every test; a leader predicted, or
   !> one that explains most of the fit tests' gap, does not
   subroutine test_held_fit_rule(error)
      type(error_type), allocatable, intent(out) :: error
      type(diagnose_result) :: res
      call held_out_middle(res, 0.109_dp, 0.172_dp, 0.410_dp, 0.070_dp)
      res%effects%significant = .true.
      res%effects%confirmed = [.false., .true.]
      res%effects%shrink_fit = [1.0_dp, 0.126_dp]
      res%effects(2)%held_fitted = .true.
      res%leading = 2
      call check(error, held_fit_only(res) .and. joint_reason(res, .false.) == joint_held_fit, &
                 'fit tests quiet, the leader fitted to the held-out test')
      if (allocated(error)) return
      ! The refit table says what its confirmation rests on
      call check(error, index(verdict_of(res%effects(2), res), 'met the held-out tests by its values fitted '// &
                 'to them: ') == 1, verdict_of(res%effects(2), res))
      if (allocated(error)) return
      res%effects(2)%held_fitted = .false.
      call check(error, index(verdict_of(res%effects(2), res), 'confirmed: ') == 1, verdict_of(res%effects(2), res))
      if (allocated(error)) return
      res%held = .false.
      call check(error, index(verdict_of(res%effects(2), res), 'fitted to every test: ') == 1, &
                 verdict_of(res%effects(2), res))
      if (allocated(error)) return
      res%held = [.false., .true., .false.]
      res%effects(2)%held_fitted = .true.
      call check(error, .not. joint_wanted(res, .true.), 'the joint stage is not run twice')
      if (allocated(error)) return
      res%gap_fit = 0.323_dp
      res%floor_fit = 0.160_dp
      call check(error, held_fit_only(res), 'it removes 12.6 % of the fit tests'' gap')
      if (allocated(error)) return
      res%effects(2)%shrink_fit = 0.95_dp
      call check(error, .not. held_fit_only(res), 'it removes most of the fit tests'' gap')
      if (allocated(error)) return
      res%effects(2)%shrink_fit = 0.126_dp
      res%effects(2)%held_fitted = .false.
      call check(error, .not. held_fit_only(res), 'a predicted leader stands')
      if (allocated(error)) return
      res%effects(2)%held_fitted = .true.
      res%gap_held = 0.05_dp
      call check(error, .not. held_fit_only(res), 'the held-out tests show no gap')
   end subroutine test_held_fit_rule

   !> Nothing confirmed, both sets' gaps below their floors, but an effect lowers the fit
   !> tests' BIC by 587 and does not carry to the held-out tests (a softening of 0.11 fitted
   !> as a hardening with the relaxation test held out): every test is fitted together; an
   !> effect that is not significant, or implausible, does not ask for it
   subroutine test_open_below_floor(error)
      type(error_type), allocatable, intent(out) :: error
      type(diagnose_result) :: res
      call held_out_middle(res, 0.05_dp, 0.16_dp, 0.0_dp, 0.20_dp)
      res%gap_held_noise = 0.0_dp
      res%floor_held_noise = 0.07_dp
      res%effects%significant = [.true., .false.]
      res%effects%dbic = [-587.0_dp, -3.0_dp]
      res%effects%shrink_fit = [1.0_dp, 0.1_dp]
      res%leading = 0
      call check(error, joint_wanted(res, .false.), 'a significant effect that does not carry')
      if (allocated(error)) return
      res%effects(1)%plausible = .false.
      call check(error, .not. joint_wanted(res, .false.), 'an implausible one does not count')
      if (allocated(error)) return
      res%effects(1)%plausible = .true.
      res%effects(1)%significant = .false.
      call check(error, .not. joint_wanted(res, .false.), 'nothing significant, both sets quiet')
      if (allocated(error)) return
      ! A second back stress confirmed for 67 % of a structured fit gap, a softening better by
      ! BIC 406 that does not carry: every test fitted together decides
      res%gap_fit = 0.266_dp
      res%floor_fit = 0.184_dp
      res%gap_held = 0.192_dp
      res%floor_held = 0.084_dp
      res%effects%significant = .true.
      res%effects%confirmed = [.false., .true.]
      res%effects%dbic = [-713.1_dp, -306.7_dp]
      res%effects%shrink_fit = [1.0_dp, 0.672_dp]
      res%leading = 2
      call check(error, form_beats_leader(res) == 1 .and. joint_reason(res, .false.) == joint_form_beats, &
                 'a better form on the fit tests than the leader''s')
      if (allocated(error)) return
      res%effects(2)%shrink_fit = 0.9_dp
      res%effects(2)%shrink_held = 1.0_dp
      call check(error, form_beats_leader(res) == 0, 'the leader explains most of the fit tests'' gap '// &
                 'and its prediction all of the held-out tests''')
      if (allocated(error)) return
      ! ... but not when its prediction leaves the held-out tests a rest above their floor (a
      ! hardening named for 86 % of the LCF test's gap, the rest 39 times its floor, where a
      ! fast second back stress, better by BIC 10.1, had made the LCF test worse)
      res%effects(2)%shrink_held = 0.861_dp
      res%gap_held = 107.2_dp
      res%floor_held = 0.381_dp
      call check(error, form_beats_leader(res) == 1 .and. joint_reason(res, .false.) == joint_form_beats, &
                 'a better form on the fit tests than that of a leader whose prediction falls short')
      if (allocated(error)) return
      res%effects(2)%shrink_held = 0.999_dp
      call check(error, form_beats_leader(res) == 0, 'the prediction leaves the held-out tests at their floor')
      if (allocated(error)) return
      res%gap_held = 0.192_dp
      res%floor_held = 0.084_dp
      res%effects(2)%shrink_held = 0.0_dp
      res%effects(2)%shrink_fit = 0.672_dp
      res%effects(1)%dbic = -310.0_dp
      call check(error, form_beats_leader(res) == 0, 'not better by the margin')
   end subroutine test_open_below_floor

   !> The second back stress's search box holds a saturation H3/gamma3 of the peak stress up
   !> to gamma3's own box end: H3's box stopped at 1000 times the peak, which capped the
   !> saturation at 0.1 of it for gamma3 = 1e4 (the Alloy 617 tests want 0.26 at gamma3 4200,
   !> and the refit ran to that end). Every parameter's box is the catalogue's.
   subroutine test_backstress2_box(error)
      type(error_type), allocatable, intent(out) :: error
      type(fit_problem) :: prob
      type(effect_problem) :: ep
      type(effect_info) :: cat(n_effects)
      real(dp), allocatable :: lo(:), hi(:)
      real(dp), parameter :: peak = 20.0_dp  ! ksi, the deck's unit
      integer :: nc, k
      call thesis_problem(prob, error)
      if (allocated(error)) return
      cat = effect_catalogue(peak)
      k = effect_index('backstress2')
      call new_effect_problem(prob, [1], k, test_effects(), peak, ep)
      call ep%bounds(lo, hi)
      nc = size(prob%idx)
      call check(error, size(hi) == nc + 2 .and. all(lo(nc + 1:) == 0.0_dp), 'H3 and gamma3 free, from zero')
      if (allocated(error)) return
      call check(error, hi(nc + 1)*ep%pscale(1) >= peak*hi(nc + 2)*ep%pscale(2), 'H3''s box ends at '// &
                 real_str(hi(nc + 1)*ep%pscale(1), 'es10.3')//' ksi: a saturation of the peak at gamma3 = '// &
                 real_str(hi(nc + 2)*ep%pscale(2), 'es10.3')//' is out of reach')
      if (allocated(error)) return
      call check(error, all(hi(nc + 1:) == cat(k)%box), 'the box is not the catalogue''s')
      if (allocated(error)) return
      k = effect_index('temperature')
      call new_effect_problem(prob, [1], k, test_effects(), peak, ep)
      call ep%bounds(lo, hi)
      call check(error, size(hi) > nc .and. all(lo(nc + 1:) == -cat(k)%box(1)) .and. all(hi(nc + 1:) == cat(k)%box(1)), &
                 'a signed parameter''s box is not the catalogue''s both ways')
   end subroutine test_backstress2_box

   !> An effect fitted to one test with the constants fixed (a held-out test's own parameters,
   !> a specimen's) starts from zero and from plus and minus its low end in that test: three
   !> starts for a temperature offset (5 K, either sign), two for a lag (0.1 s; minus it is
   !> clipped onto zero, a start already taken); the problem's own parameters left as they were
   subroutine test_low_end_starts(error)
      type(error_type), allocatable, intent(out) :: error
      type(fit_problem) :: prob
      type(effect_problem) :: ep
      type(effect_info) :: cat(n_effects)
      real(dp), allocatable :: lo(:), hi(:), xs(:, :), p0(:)
      real(dp), parameter :: peak = 20.0_dp  ! ksi, the deck's unit
      integer :: k, nt
      call thesis_problem(prob, error)
      if (allocated(error)) return
      cat = effect_catalogue(peak)
      nt = size(prob%targets)
      k = effect_index('temperature')
      call new_effect_problem(prob, [1], k, test_effects(), peak, ep, free_constants=.false.)
      call ep%bounds(lo, hi)
      p0 = ep%p0
      call distinct_starts(ep, low_end_starts(ep%p0, low_end_deltas(ep, cat(k), [1])), lo, hi, xs)
      call check(error, size(xs, 2) == 3 .and. size(xs, 1) == nt, 'temperature: '//str(size(xs, 2))// &
                 ' starts of '//str(size(xs, 1))//' parameters')
      if (allocated(error)) return
      call check(error, all(xs(:, 1) == 0.0_dp) .and. abs(xs(1, 2)*ep%pscale(1) - cat(k)%low(1)) < 1.0e-12_dp &
                 .and. xs(1, 3) == -xs(1, 2) .and. all(xs(2:, 2:) == 0.0_dp), &
                 'temperature: zero, then plus and minus '//real_str(cat(k)%low(1), 'f5.1')//' K in the first test only')
      if (allocated(error)) return
      call check(error, all(ep%p0 == p0), 'the problem''s parameters changed')
      if (allocated(error)) return
      k = effect_index('lag')
      call new_effect_problem(prob, [1], k, test_effects(), peak, ep, free_constants=.false.)
      call ep%bounds(lo, hi)
      call distinct_starts(ep, low_end_starts(ep%p0, low_end_deltas(ep, cat(k), [1])), lo, hi, xs)
      call check(error, size(xs, 2) == 2, 'lag: '//str(size(xs, 2))//' starts, not zero and its low end')
      if (allocated(error)) return
      call check(error, abs(xs(1, 2)*ep%pscale(1) - cat(k)%low(1)) < 1.0e-12_dp, 'lag: not its low end')
   end subroutine test_low_end_starts

   !> A batch of points of a temperature offset per test (the thesis's two tests, the
   !> constants free): each test is simulated only where the constants and its own offset
   !> are new to the batch. Offsets [d, 0], [0, d], [d, d]: the first point simulates both
   !> tests, the second both (each sees a new offset), the third none (test 1 sees the
   !> first's, test 2 the second's): 4 simulations for 3 points, and the same residuals bit
   !> for bit as each point evaluated alone; the second batch, the last point again, none
   subroutine test_rows_reused(error)
      type(error_type), allocatable, intent(out) :: error
      type(fit_problem) :: prob
      type(effect_problem) :: ep, alone
      type(uerror), allocatable :: e
      real(dp), allocatable :: x0(:), xs(:, :), rs(:, :), fs(:), r(:)
      logical :: ok(3), ok1
      integer :: j, nc
      call thesis_problem(prob, error)
      if (allocated(error)) return
      call new_effect_problem(prob, [1, 2], effect_index('temperature'), test_effects(), 20.0_dp, ep)
      alone = ep
      x0 = ep%start()
      nc = size(x0) - 2
      call check(error, nc == size(prob%idx), 'not one offset per test beside the constants')
      if (allocated(error)) return
      xs = spread(x0, 2, 3)
      xs(nc + 1, [1, 3]) = 0.5_dp
      xs(nc + 2, [2, 3]) = 0.5_dp
      allocate (rs(ep%nres(), 3), fs(3), r(ep%nres()))
      call ep%residuals(xs, rs, fs, ok, e)
      call check(error, .not. allocated(e) .and. all(ok), 'the batch failed')
      if (allocated(error)) return
      call check(error, ep%nsims == 4 .and. ep%nevals == 3, str(ep%nsims)//' tests simulated for '// &
                 str(ep%nevals)//' points, not 4 for 3')
      if (allocated(error)) return
      do j = 1, 3
         call alone%residual_at(xs(:, j), r, ok1)
         call check(error, ok1 .and. all(r == rs(:, j)), 'point '//str(j)//': not the rows of its own simulation')
         if (allocated(error)) return
      end do
      call check(error, any(rs(:, 3) /= rs(:, 1)) .and. any(rs(:, 3) /= rs(:, 2)), 'the offsets change nothing')
      if (allocated(error)) return
      call ep%residuals(xs(:, 3:3), rs(:, 1:1), fs(1:1), ok(1:1), e)
      call ep%residuals(xs(:, 3:3), rs(:, 2:2), fs(1:1), ok(1:1), e)
      call check(error, ep%nsims == 6 .and. all(rs(:, 2) == rs(:, 3)), str(ep%nsims - 4)// &
                 ' tests simulated for a point twice alone, not 2')
   end subroutine test_rows_reused

   !> The fit problem of the thesis's run 2 (decks/thesis-run2.nml)
   subroutine thesis_problem(prob, error)
      type(fit_problem), intent(out) :: prob
      type(error_type), allocatable, intent(out) :: error
      type(run_config) :: cfg
      type(uerror), allocatable :: e
      call read_config('decks/thesis-run2.nml', cfg, e)
      if (.not. allocated(e)) call setup_problem(cfg, prob, e)
      call check(error, .not. allocated(e), 'the thesis deck is set up')
   end subroutine thesis_problem

   !> An effect parameter is flagged at its search box's outer ends (a second back stress's H3
   !> at its upper end, a temperature offset at its negative end), not at a lower end of
   !> zero that a parameter which cannot be negative may reach (no lag); a constant at its
   !> &fit bound is flagged within 1e-6 of it in log10 units (where a search that ran away ends)
   subroutine test_box_end(error)
      type(error_type), allocatable, intent(out) :: error
      integer :: got(6)
      got = at_box_end([1.7463e5_dp, 1.7462e5_dp, 0.0_dp, -50.0_dp, 3.0_dp, 0.07_dp], &
                       [0.0_dp, 0.0_dp, 0.0_dp, -50.0_dp, -50.0_dp, 0.0_dp], &
                       [1.7463e5_dp, 1.7463e5_dp, 70.0_dp, 50.0_dp, 50.0_dp, 70.0_dp])
      call check(error, all(got == [1, 0, 0, -1, 0, 0]), 'effect parameters at the box''s ends')
      if (allocated(error)) return
      ! A constant 1.5 % inside its bound (0.0065 in log10) is not at it; one on it is
      got(1:5) = at_bound([2.0_dp, 3.0_dp, 3.0_dp - 0.0065_dp, -3.0_dp, -3.0_dp + 5.0e-7_dp], &
                          spread(-3.0_dp, 1, 5), spread(3.0_dp, 1, 5))
      call check(error, all(got(1:5) == [0, 1, 0, -1, -1]), 'constants at a bound of &fit, and which')
   end subroutine test_box_end

   !> One rule of plausibility for both diagnoses: a temperature offset of 177 K [150, 204] is
   !> beyond its 25 K limit, 25.1 K [24.6, 25.6] is not, 30 K with an open end is judged by
   !> its value; a softening by its reach; a second back stress whose H3 has no limit by its
   !> saturation against the peak (597 MPa against 176: beyond), and one that does not
   !> saturate (gamma3 = 0) beyond it; a parameter without a limit leaves the others to decide
   subroutine test_beyond_limit(error)
      type(error_type), allocatable, intent(out) :: error
      type(effect_info) :: cat(n_effects)
      type(effect_problem) :: ep
      real(dp) :: r, reach, saturation
      cat = effect_catalogue(176.0_dp)
      associate (dt => cat(effect_index('temperature')), soft => cat(effect_index('softening')), &
                 bs2 => cat(effect_index('backstress2')))
         r = beyond_limit(dt, [1, 1], [177.0_dp, 25.1_dp], [150.0_dp, 24.6_dp], [204.0_dp, 25.6_dp], &
                          [.false., .false.], 0.0_dp, 0.0_dp)
         call check(error, abs(r - 6.0_dp) < 1.0e-12_dp, 'two tests, one beyond doubt: '//real_str(r, 'f0.4'))
         if (allocated(error)) return
         r = beyond_limit(dt, [1], [25.1_dp], [24.6_dp], [25.6_dp], [.false.], 0.0_dp, 0.0_dp)
         call check(error, r < 1.0_dp, 'at the limit: '//real_str(r, 'f0.4'))
         if (allocated(error)) return
         r = beyond_limit(dt, [1], [30.0_dp], [28.0_dp], [32.0_dp], [.true.], 0.0_dp, 0.0_dp)
         call check(error, abs(r - 1.2_dp) < 1.0e-12_dp, 'an open end: by its value: '//real_str(r, 'f0.4'))
         if (allocated(error)) return
         r = beyond_limit(soft, [1, 2], [0.9_dp, 50.0_dp], [0.8_dp, 40.0_dp], [1.0_dp, 60.0_dp], &
                          [.false., .false.], 0.2_dp, 0.0_dp)
         call check(error, abs(r - 0.2_dp/soft%plausible(1)) < 1.0e-12_dp, 'softening by its reach: '// &
                    real_str(r, 'f0.4'))
         if (allocated(error)) return
         r = beyond_limit(bs2, [1, 2], [1.7463e5_dp, 292.0_dp], [1.0e5_dp, 200.0_dp], &
                          [2.0e5_dp, 400.0_dp], [.false., .false.], 0.0_dp, 597.0_dp/176.0_dp)
         call check(error, abs(r - 597.0_dp/176.0_dp) < 1.0e-12_dp, 'back stress by its saturation: '// &
                    real_str(r, 'f0.4'))
         if (allocated(error)) return
         ! H3 = 866 MPa at gamma3 = 0 never saturates, at 300 it saturates at 2.9 MPa
         call limit_measures(bs2, ep, [0.0_dp], [866.0_dp, 0.0_dp], 176.0_dp, reach, saturation)
         r = beyond_limit(bs2, [1, 2], [866.0_dp, 0.0_dp], [773.0_dp, 0.0_dp], [960.0_dp, 2.05_dp], &
                          [.false., .false.], reach, saturation)
         call check(error, r > 1.0_dp, 'a back stress without saturation within its limit: '//real_str(r, 'es10.3'))
         if (allocated(error)) return
         call limit_measures(bs2, ep, [0.0_dp], [866.0_dp, 300.0_dp], 176.0_dp, reach, saturation)
         call check(error, abs(saturation - 866.0_dp/300.0_dp/176.0_dp) < 1.0e-15_dp, &
                    'saturation of gamma3 300: '//real_str(saturation, 'es10.3'))
      end associate
   end subroutine test_beyond_limit

   !> Where the global starts found a lower baseline (494.8 against 533.7, noise 0.5), the
   !> refits' shares are of the structured gap there: 494.3, so an effect that leaves 240.3
   !> removes 51.4 %, not the 54.9 % of the first baseline's gap; without it the first's gap
   subroutine test_gap_fit_ref(error)
      type(error_type), allocatable, intent(out) :: error
      type(diagnose_result) :: res
      res%f0 = 533.7_dp
      res%gap_fit = 533.2_dp
      res%f0_global = 494.8_dp
      res%global = .false.
      call check(error, gap_fit_ref(res) == 533.2_dp, 'no global stage: the baseline''s gap')
      if (allocated(error)) return
      res%global = .true.
      call check(error, abs(gap_fit_ref(res) - 494.3_dp) < 1.0e-9_dp, 'the lower baseline''s gap: '// &
                 real_str(gap_fit_ref(res), 'f0.3'))
      if (allocated(error)) return
      call check(error, abs(1.0_dp - 240.3_dp/gap_fit_ref(res) - 0.5139_dp) < 1.0e-4_dp, 'share')
      if (allocated(error)) return
      res%f0_global = 600.0_dp
      call check(error, gap_fit_ref(res) == 533.2_dp, 'a global stage that found no lower baseline')
   end subroutine test_gap_fit_ref

   !> The verdict's note of a leader whose refit ran to search bounds: its constants (ran
   !> away) and its own parameters (not determined); nothing where none did
   subroutine test_bound_note(error)
      type(error_type), allocatable, intent(out) :: error
      type(diagnose_result) :: res
      type(effect_outcome) :: e
      character(len=:), allocatable :: text
      res%cnames = [character(len=2) :: 'A1', 'B', 'n']
      e%c = [1.16e-3_dp, 1.03e12_dp, 4.0_dp]
      e%c_bound = [1, -1, 0]
      e%pname = [character(len=40) :: 'H3', 'gamma3']
      e%p = [1.7609e5_dp, 3.9968e3_dp]
      e%p_bound = [1, 0]
      e%punit = [character(len=12) :: 'stress', '-']
      res%stress_unit = 'MPa'
      text = bound_note(res, e)
      ! (which end each is at: a fit that ran to B's lower bound ran the other way)
      call check(error, index(text, 'ran away: A1 = 1.160E-03 (upper), B = 1.030E+12 (lower) at a search '// &
                 'bound') > 0 .and. index(text, 'H3 = 1.761E+05 MPa (upper) at its search bound, not determined') > 0 .and. &
                 index(text, 'gamma3') == 0 .and. index(text, ' n ') == 0, text)
      if (allocated(error)) return
      e%c_bound = 0
      e%p_bound = 0
      call check(error, len(bound_note(res, e)) == 0, 'no bound: '//bound_note(res, e))
   end subroutine test_bound_note

   !> The largest of a per-test effect's values fitted to the held-out tests against its
   !> limit, named with its test (a drift of a held-out test at 3 times it); none for a
   !> global effect's values, which are not per test
   subroutine test_held_values(error)
      type(error_type), allocatable, intent(out) :: error
      type(effect_info) :: cat(n_effects)
      real(dp) :: worst
      character(len=:), allocatable :: what
      integer :: k
      cat = effect_catalogue(176.0_dp)
      k = effect_index('drift')
      call judge_held_values(cat(k), [character(len=6) :: 'E-12', 'E-28', '43-3'], [.false., .false., .true.], &
                             [2.0e-5_dp, 1.0e-6_dp, -3.0e-5_dp], worst, what)
      call check(error, abs(worst - 3.0_dp) < 1.0e-12_dp .and. what == 'd 43-3', &
                 'a held-out drift of 3 times its limit: '//what)
      if (allocated(error)) return
      call judge_held_values(cat(k), [character(len=6) :: 'E-12', 'E-28', '43-3'], [.true., .false., .true.], &
                             [2.0e-6_dp, 1.0e-6_dp, 1.0e-6_dp], worst, what)
      call check(error, abs(worst - 0.2_dp) < 1.0e-12_dp .and. what == 'd E-12', &
                 'the larger of two held-out drifts: '//what)
      if (allocated(error)) return
      call judge_held_values(cat(effect_index('initial')), [character(len=6) :: 'E-12', 'E-28'], &
                             [.true., .true.], [500.0_dp, 0.0_dp], worst, what)
      call check(error, worst == 0.0_dp .and. len(what) == 0, 'a global effect: '//what)
   end subroutine test_held_values

   !> The key of a problem holds every value of its effects, component by component: as many
   !> values as the type has 8-byte slots, and a change of the last one shows
   subroutine test_effect_reals(error)
      type(error_type), allocatable, intent(out) :: error
      type(test_effects) :: a, b
      b%drift = 1.0e-6_dp
      call check(error, size(effect_reals(a))*storage_size(1.0_dp) >= storage_size(a), &
                 'a component of test_effects left out of effect_reals')
      if (allocated(error)) return
      call check(error, any(effect_reals(a) /= effect_reals(b)), 'the drift in the key')
   end subroutine test_effect_reals

   !> An interval about a lower point than the estimate's that leaves the estimate out
   !> (dE/E = -0.181 [-0.224, -0.191]) is open on the estimate's side; one that holds it stays
   subroutine test_open_beyond_estimate(error)
      type(error_type), allocatable, intent(out) :: error
      logical :: lo_open(3), hi_open(3)
      lo_open = .false.
      hi_open = [.false., .false., .true.]
      call open_beyond_estimate([-0.181_dp, 1.0_dp, -2.0_dp], [-0.224_dp, 0.5_dp, -1.0_dp], &
                                [-0.191_dp, 1.5_dp, 3.0_dp], lo_open, hi_open)
      call check(error, all(hi_open .eqv. [.true., .false., .true.]) .and. &
                 all(lo_open .eqv. [.false., .false., .true.]), 'the ends on the estimate''s side open')
   end subroutine test_open_beyond_estimate

   !> A fitted magnitude is implausible only when its interval lies beyond the limit: a
   !> temperature offset fitted at 25.1 K [24.6, 25.6] against a limit of 25 K is at the
   !> limit; 177 K [150, 204] is beyond it; an interval across zero or not finite leaves the
   !> fitted ratio
   subroutine test_beyond_doubt(error)
      type(error_type), allocatable, intent(out) :: error
      real(dp) :: r
      r = ratio_beyond_doubt(25.1_dp/25.0_dp, -25.1_dp, -25.6_dp, -24.6_dp)
      call check(error, abs(r - 24.6_dp/25.0_dp) < 1.0e-12_dp .and. r < 1.0_dp, 'at the limit: '//real_str(r, 'f0.4'))
      if (allocated(error)) return
      r = ratio_beyond_doubt(177.0_dp/25.0_dp, 177.0_dp, 150.0_dp, 204.0_dp)
      call check(error, abs(r - 6.0_dp) < 1.0e-12_dp, 'well beyond the limit: '//real_str(r, 'f0.4'))
      if (allocated(error)) return
      r = ratio_beyond_doubt(177.0_dp/25.0_dp, 177.0_dp, -300.0_dp, 654.0_dp)
      call check(error, abs(r - 177.0_dp/25.0_dp) < 1.0e-12_dp, 'undetermined: the fitted ratio')
      if (allocated(error)) return
      r = ratio_beyond_doubt(1.2_dp, 30.0_dp, ieee_value(1.0_dp, ieee_quiet_nan), 31.0_dp)
      call check(error, abs(r - 1.2_dp) < 1.0e-12_dp, 'no interval: the fitted ratio')
   end subroutine test_beyond_doubt

   !> The verdict says what the end points of a refit that the fit tests cannot tell apart
   !> carry of the held-out gap (the creep matrix's softening: 54.7 % from the end point
   !> used, 88.2 % from one within BIC 10 of it), and says nothing where they agree to 5 %
   !> of the gap or there are none
   subroutine test_alike_note(error)
      type(error_type), allocatable, intent(out) :: error
      type(effect_outcome) :: e
      character(len=:), allocatable :: text
      e%shrink_held = 0.547_dp
      e%n_alike = 4
      e%shrink_alike_lo = 0.547_dp
      e%shrink_alike_hi = 0.882_dp
      text = alike_note(e)
      call check(error, index(text, 'responses of 5 end points') > 0 .and. index(text, '54.7 to 88.2 %') > 0 .and. &
                 index(text, 'leave the held-out prediction open') > 0, 'no range stated: '//text)
      if (allocated(error)) return
      e%shrink_alike_hi = 0.590_dp
      call check(error, len(alike_note(e)) == 0, 'a range of 4 % of the gap stated: '//alike_note(e))
      if (allocated(error)) return
      e%shrink_alike_hi = 0.882_dp
      e%n_alike = 0
      call check(error, len(alike_note(e)) == 0, 'a range stated without other end points')
   end subroutine test_alike_note

   !> A refit starts from the lowest screening end point of the other sign too, and its
   !> further starts of the constants take that end point's parameters as well as the
   !> lowest's (the end points of the softening case in other_sign: the lowest a hardening,
   !> the third a softening); a run that found nothing below the baseline gives its start;
   !> an effect whose end points all have one sign, or no
   !> parameter, starts as before
   subroutine test_both_signs(error)
      type(error_type), allocatable, intent(out) :: error
      type(effect_outcome) :: e
      real(dp) :: xc(2, 3)
      real(dp), allocatable :: xs(:, :)
      e%x = [0.1_dp, 0.2_dp, -0.874_dp, 0.340_dp]
      e%x_alt = reshape([0.3_dp, 0.4_dp, -0.219_dp, 13.5_dp, 0.5_dp, 0.6_dp, -0.215_dp, 0.87_dp, &
                         0.7_dp, 0.8_dp, 0.293_dp, 2.80_dp, 0.9_dp, 1.0_dp, 0.006_dp, 0.0_dp], [4, 4])
      xc = reshape([1.0_dp, 2.0_dp, 3.0_dp, 4.0_dp, 5.0_dp, 6.0_dp], [2, 3])
      call check(error, other_sign(e, 2) == 3, 'the lowest softening end point not found: '// &
                 str(other_sign(e, 2)))
      if (allocated(error)) return
      xs = with_params(e, xc)
      call check(error, size(xs, 2) == 6, 'further starts of the constants not doubled: '//str(size(xs, 2)))
      if (allocated(error)) return
      call check(error, all(xs(1:2, 1:3) == xc) .and. all(xs(1:2, 4:6) == xc) .and. &
                 all(xs(3, 1:3) == -0.874_dp) .and. all(xs(3:4, 4:6) == spread([0.293_dp, 2.80_dp], 2, 3)), &
                 'further starts not the constants with each basin''s parameters')
      if (allocated(error)) return
      e%x_alt(3, 3) = -0.293_dp
      e%x_alt(3, 4) = -0.006_dp
      call check(error, other_sign(e, 2) == 0 .and. size(with_params(e, xc), 2) == 3, &
                 'end points of one sign took another basin')
      if (allocated(error)) return
      ! A run that found nothing below the baseline keeps its start as its basin's point: the
      ! softening started at +0.05, b = 100 that ended at a = 0.005, b = 0.001 (the baseline's
      ! objective) is the other sign's basin to try, at its start's parameters
      xs = basin_points(reshape([0.3_dp, 0.4_dp, -0.219_dp, 13.5_dp, 0.9_dp, 1.0_dp, 0.005_dp, 0.001_dp], [4, 2]), &
                        reshape([0.1_dp, 0.2_dp, -0.05_dp, 10.0_dp, 0.1_dp, 0.2_dp, 0.05_dp, 100.0_dp], [4, 2]), &
                        [0.80_dp, 1.0102_dp], 1.0102_dp)
      call check(error, all(xs(:, 1) == [0.3_dp, 0.4_dp, -0.219_dp, 13.5_dp]) .and. &
                 all(xs(:, 2) == [0.1_dp, 0.2_dp, 0.05_dp, 100.0_dp]), &
                 'a run that found nothing kept its end point, or one that did its start')
      if (allocated(error)) return
      e%x_alt = xs
      call check(error, other_sign(e, 2) == 2, 'the start of the other sign''s run not taken: '// &
                 str(other_sign(e, 2)))
      if (allocated(error)) return
      xs = with_params(e, xc)
      call check(error, all(xs(3:4, 4:6) == spread([0.05_dp, 100.0_dp], 2, 3)), &
                 'further starts not at the other sign''s start parameters')
      if (allocated(error)) return
      ! No effect parameter in x (the constants alone)
      e%x = [0.1_dp, 0.2_dp]
      e%x_alt = reshape([0.3_dp, -0.4_dp], [2, 1])
      call check(error, other_sign(e, 2) == 0, 'a constant''s sign taken for the effect''s')
   end subroutine test_both_signs

   !> The second back stress's screening starts span its recovery rates (a fit stays in the
   !> basin of the rate it starts from: on Alloy 617's tests every start at gamma3 = 200 ended
   !> near the baseline, one at 4000 at 41 % of its objective), and a refit starts from the
   !> lowest end point of each rate's starts, the leading one's first, each rate once
   subroutine test_rate_rungs(error)
      type(error_type), allocatable, intent(out) :: error
      type(effect_outcome) :: e
      real(dp), allocatable :: ps(:, :), sat(:)
      ps = backstress2_starts(150.0_dp, 200.0_dp)
      call check(error, all(ps(:, 1) == [1.5_dp, 200.0_dp]), 'the first start is not the near-zero one')
      if (allocated(error)) return
      sat = ps(1, 2:)/ps(2, 2:)/150.0_dp
      ! (a fast second back stress, gamma3 4474 and 4898, was missed from rates up to 2000)
      call check(error, minval(ps(2, 2:)) <= 100.0_dp .and. maxval(ps(2, 2:)) >= 5000.0_dp .and. &
                 all(abs(sat - 0.03_dp) < 1.0e-12_dp .or. abs(sat - 0.1_dp) < 1.0e-12_dp) .and. &
                 count(abs(sat - 0.1_dp) < 1.0e-12_dp) == count(abs(sat - 0.03_dp) < 1.0e-12_dp), &
                 'starts do not span rates 100-5000 at saturations of 3 and 10 % of the peak')
      if (allocated(error)) return
      e%x = [0.1_dp, 0.5_dp, 0.4_dp]
      e%x_alt = reshape([0.2_dp, 0.6_dp, 0.1_dp, 0.3_dp, 7.0_dp, 2.0_dp, 0.4_dp, 0.1_dp, 0.4_dp, &
                         0.5_dp, 0.0_dp, 0.1_dp, 0.6_dp, 8.0_dp, 2.0_dp], [3, 5])
      call check(error, size(rate_rungs(e)) == 1, 'rungs without the starts'' rates')
      if (allocated(error)) return
      e%rate_start = 400.0_dp
      e%rate_alt = [100.0_dp, 2000.0_dp, 400.0_dp, 100.0_dp, 2000.0_dp]
      call check(error, all(rate_rungs(e) == [0, 1, 2]), 'not the lowest end point of each rate once: '// &
                 str(size(rate_rungs(e))))
   end subroutine test_rate_rungs

   !> An effect judged beyond its limit is refitted with its rate held only where the rate
   !> is undetermined (the LCF-held-out case: a second back stress with gamma3 25 [-2.8,
   !> 52.7]), not where the data fix it, not for a plausible or an already held refit; the
   !> rates held are the second back stress's gamma3 and the softening's b, no other
   !> effect's parameter
   subroutine test_rate_held(error)
      type(error_type), allocatable, intent(out) :: error
      type(diagnose_context) :: ctx
      type(effect_outcome) :: e
      integer :: k
      ctx%cat = effect_catalogue(20.0_dp)
      e%k = effect_index('backstress2')
      e%plausible = .false.
      e%p = [673.4_dp, 24.9_dp]
      e%p_lo = [513.6_dp, -2.84_dp]
      e%p_hi = [833.2_dp, 52.7_dp]
      call check(error, rate_undetermined(ctx, e) .and. rate_doubt(ctx, e) == rate_open, &
                 'gamma3 spanning zero not held, or not for that')
      if (allocated(error)) return
      e%p_hi(2) = ieee_value(1.0_dp, ieee_quiet_nan)
      e%p_lo(2) = 10.0_dp
      call check(error, rate_undetermined(ctx, e), 'gamma3 with an interval not finite not held')
      if (allocated(error)) return
      e%p_lo(2) = 10.0_dp
      e%p_hi(2) = 40.0_dp
      call check(error, .not. rate_undetermined(ctx, e), 'gamma3 the data fix held')
      if (allocated(error)) return
      ! A closed interval about a rate at the end of its search box does not hold
      e%p_bound = [0, 1]
      call check(error, rate_undetermined(ctx, e) .and. rate_doubt(ctx, e) == rate_at_end, &
                 'gamma3 at the end of its box not held, or not for that')
      if (allocated(error)) return
      e%p_bound = [1, 0]
      call check(error, .not. rate_undetermined(ctx, e), 'held for H3 at its bound')
      if (allocated(error)) return
      deallocate (e%p_bound)
      e%p_lo(2) = -2.84_dp
      e%plausible = .true.
      call check(error, .not. rate_undetermined(ctx, e), 'a plausible refit held')
      if (allocated(error)) return
      e%plausible = .false.
      e%held = .true.
      call check(error, .not. rate_undetermined(ctx, e), 'a held refit held again')
      if (allocated(error)) return
      e%held = .false.
      ! A softening far beyond its limit whose rate b the data leave open
      e%k = effect_index('softening')
      e%p = [-15.0_dp, 40.0_dp]
      e%p_lo = [-40.0_dp, 3.0_dp]
      e%p_hi = [-2.0_dp, ieee_value(1.0_dp, ieee_positive_inf)]
      call check(error, rate_undetermined(ctx, e), 'a softening''s open b not held')
      if (allocated(error)) return
      e%p_hi(2) = 400.0_dp
      call check(error, .not. rate_undetermined(ctx, e), 'a softening''s b the data fix held')
      if (allocated(error)) return
      do k = 1, size(ctx%cat)
         select case (trim(ctx%cat(k)%name))
         case ('softening', 'backstress2')
            call check(error, held_rate(ctx%cat(k)) == 2, trim(ctx%cat(k)%name)//'''s rate is not its second parameter')
         case default
            call check(error, held_rate(ctx%cat(k)) == 0, trim(ctx%cat(k)%name)//' has a rate to hold')
         end select
         if (allocated(error)) return
      end do
   end subroutine test_rate_held

   !> The chi-square tails the power statement uses and the critical values of a
   !> likelihood-ratio region, against closed forms and scipy 1.x (scipy.special.gammaincc,
   !> scipy.stats.chi2.sf, isf and ncx2.sf, printed to 17 digits)
   subroutine test_chi2_tails(error)
      type(error_type), allocatable, intent(out) :: error
      real(dp) :: got(9), want(9)
      got = [gamma_q(1.0_dp, 3.7_dp), chi2_sf(5.0_dp, 2.0_dp), gamma_q(2.5_dp, 0.7_dp), &
             gamma_q(2.5_dp, 9.0_dp), chi2_sf(16.0_dp, 3.0_dp), ncx2_sf(20.0_dp, 2.0_dp, 15.0_dp), &
             ncx2_sf(16.0_dp, 1.0_dp, 4.0_dp), ncx2_sf(30.0_dp, 7.0_dp, 40.0_dp), &
             ncx2_sf(50.0_dp, 3.0_dp, 2000.0_dp)]
      ! k = 1: P(|z + sqrt(lambda)| > sqrt(x)) = Phi(-sqrt(x) - sqrt(lambda)) + Phi(sqrt(lambda) - sqrt(x))
      want = [exp(-3.7_dp), exp(-2.5_dp), 0.924313272801667_dp, 0.0029464045878802923_dp, &
              0.0011339842897853216_dp, 0.31634469213011623_dp, &
              0.5_dp*erfc(6.0_dp/sqrt(2.0_dp)) + 0.5_dp*erfc(2.0_dp/sqrt(2.0_dp)), &
              0.9129580078094358_dp, 1.0_dp]
      call check(error, all(abs(got - want) <= 1.0e-12_dp + 1.0e-10_dp*abs(want)), 'chi-square tails: '// &
                 real_str(maxval(abs(got - want)), 'es9.2')//' off')
      if (allocated(error)) return
      ! The noncentral tail with no signal is the central one
      call check(error, abs(ncx2_sf(16.0_dp, 3.0_dp, 0.0_dp) - want(5)) < 1.0e-15_dp, 'lambda = 0')
      if (allocated(error)) return
      ! Critical values against scipy.stats.chi2.isf (k = 2 in closed form: -2 ln p)
      got(1:4) = chi2_isf([0.05_dp, 0.05_dp, 0.05_dp, 1.0e-3_dp], [1.0_dp, 7.0_dp, 9.0_dp, 2.0_dp])
      want(1:4) = [3.8414588206941285_dp, 14.067140449340167_dp, 16.91897760462045_dp, -2.0_dp*log(1.0e-3_dp)]
      call check(error, all(abs(got(1:4) - want(1:4)) <= 1.0e-8_dp*want(1:4)), 'chi-square critical values: '// &
                 real_str(maxval(abs(got(1:4) - want(1:4))), 'es9.2')//' off')
   end subroutine test_chi2_tails

   !> Zero-width F descriptors print a leading zero and no bare point; a negative value that
   !> rounds to zero prints as zero
   subroutine test_number_format(error)
      type(error_type), allocatable, intent(out) :: error
      character(len=:), allocatable :: wide
      call check(error, real_str(0.55_dp, 'f0.2') == '0.55' .and. real_str(-0.55_dp, 'f0.2') == '-0.55' &
                 .and. real_str(6.0_dp, 'f0.0') == '6' .and. real_str(0.0_dp, 'f0.2') == '0.00' .and. &
                 real_str(-0.2_dp, 'f0.0') == '0' .and. real_str(12.5_dp, 'f0.1') == '12.5' .and. &
                 real_str(-0.004_dp, 'f0.1') == '0.0' .and. real_str(-0.04_dp, 'f6.1') == '0.0' .and. &
                 real_str(-0.06_dp, 'f0.1') == '-0.1' .and. &
                 real_str(0.5_dp, 'f6.2') == '0.50', 'real_str: '//real_str(0.55_dp, 'f0.2')//' '// &
                 real_str(6.0_dp, 'f0.0')//' '//real_str(-0.55_dp, 'f0.2'))
      if (allocated(error)) return
      ! An exponent of three digits keeps its letter (the processor writes 5.4329-167 in es11.4)
      call check(error, real_str(5.4329e-167_dp, 'es11.4') == '5.4329E-167' .and. &
                 real_str(-1.7749e159_dp, 'es11.4') == '-1.7749E+159' .and. &
                 real_str(1.5e10_dp, 'es11.4') == '1.5000E+10', 'real_str: '// &
                 real_str(5.4329e-167_dp, 'es11.4')//' '//real_str(-1.7749e159_dp, 'es11.4'))
      if (allocated(error)) return
      ! G0.d of a small or large value: d significant digits and a two-digit exponent, not the
      ! processor's 0.300000E-4; values G0.d writes without an exponent as they were
      call check(error, real_str(3.0e-5_dp, 'g0.6') == '3.00000E-05' .and. &
                 real_str(-1.25e-120_dp, 'g0.4') == '-1.250E-120' .and. &
                 real_str(2.5e7_dp, 'g0.6') == '2.50000E+07' .and. real_str(0.125_dp, 'g0.6') == &
                 '0.125000' .and. real_str(866.15_dp, 'g0.8') == '866.15000', 'g0.d: '// &
                 real_str(3.0e-5_dp, 'g0.6')//' '//real_str(-1.25e-120_dp, 'g0.4')//' '// &
                 real_str(2.5e7_dp, 'g0.6')//' '//real_str(0.125_dp, 'g0.6')//' '//real_str(866.15_dp, 'g0.8'))
      if (allocated(error)) return
      ! A number wider than a line (a runaway value in f0.1; the write had overrun its buffer
      ! and stopped the program), and one that cannot be written in the descriptor
      wide = real_str(1.0e100_dp, 'f0.1')
      call check(error, len(wide) == 103 .and. wide(1:2) == '10' .and. real_str(1.5_dp, 'i5') == '*', &
                 'wide numbers: '//str(len(wide))//' characters')
      if (allocated(error)) return
      ! An interval's end the data do not bound is 'open', but zero, a physical bound, a number
      call check(error, interval_end(129.0_dp, .true., 'es9.2') == 'open' .and. &
                 interval_end(0.0_dp, .true., 'es9.2') == '0.00E+00' .and. &
                 interval_end(81.2_dp, .false., 'es9.2') == '8.12E+01', 'interval ends: '// &
                 interval_end(129.0_dp, .true., 'es9.2')//' '//interval_end(0.0_dp, .true., 'es9.2'))
      if (allocated(error)) return
      ! Digits enough to tell a narrow interval's ends from the value
      call check(error, interval_format(12.578_dp, 12.567_dp, 12.600_dp) == 'es10.3' .and. &
                 interval_format(0.194_dp, 0.189_dp, 0.200_dp) == 'es9.2' .and. &
                 interval_format(-0.27_dp, -0.29_dp, -0.26_dp) == 'es9.2' .and. &
                 interval_format(0.0_dp, -1.0_dp, 1.0_dp) == 'es9.2' .and. &
                 interval_format(12.578_dp, 12.578_dp, 12.592_dp) == 'es10.3', 'interval digits: '// &
                 interval_format(12.578_dp, 12.567_dp, 12.600_dp)//' '//interval_format(0.194_dp, 0.189_dp, 0.200_dp))
   end subroutine test_number_format

   !> One noisy repetition each of clean data, compliance, lag and shift on a small
   !> matrix: every injected effect ranks first and clean data give no effect
   subroutine test_selfcheck(error)
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: e
      type(run_config) :: cfg
      type(diagnose_options) :: opts
      type(selfcheck_result) :: sc
      integer :: row
      call read_config(write_text('diag-selfcheck.nml', [character(len=100) :: model_groups, &
         small_matrix]), cfg, e)
      if (.not. allocated(e)) call diagnose_options_of(cfg, opts, e)
      if (.not. allocated(e)) call selfcheck_run(cfg, opts, sc, e)
      call check(error, .not. allocated(e), 'self-check failed to run')
      if (allocated(error)) return
      do row = 1, size(sc%injected)
         call check(error, sc%confusion(row, sc%injected(row)) == 1, 'injected effect '// &
                    char(48 + sc%injected(row))//' not ranked first')
         if (allocated(error)) return
      end do
   end subroutine test_selfcheck

   !> A fit deck as the self-check's matrix, its constants a search's start (the quickstart's
   !> standard guess): an injected effect's data cannot be simulated there, and the error names
   !> the deck, the effect and its magnitude, and what constants the matrix needs
   subroutine test_selfcheck_start(error)
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: e
      type(run_config) :: cfg
      type(diagnose_options) :: opts
      type(selfcheck_result) :: sc
      call read_config('decks/quickstart.nml', cfg, e)
      if (.not. allocated(e)) call diagnose_options_of(cfg, opts, e)
      call check(error, .not. allocated(e), 'the deck reads')
      if (allocated(error)) return
      call selfcheck_run(cfg, opts, sc, e)
      call check(error, allocated(e), 'a self-check at a start refused')
      if (allocated(error)) return
      call check(error, index(e%message, 'decks/quickstart.nml: self-check: its tests cannot be '// &
                 'simulated at its &constants with the injected effect ') == 1 .and. &
                 index(e%message, ' = ') > 0 .and. index(e%message, 'best.nml') > 0, e%message)
   end subroutine test_selfcheck_start
   !> What the tests could miss, said within the effects' limits: a second back stress by
   !> its saturation, a size beyond the physical limit as not found within it, a power of
   !> 0.949 as short of 0.95, and a test named only where it would find the effect more often
   subroutine test_missed_note(error)
      use usharp_diagnose_types, only: hidden_effect, hidden_size
      use usharp_effects, only: effect_catalogue, effect_info
      type(error_type), allocatable, intent(out) :: error
      type(effect_info), allocatable :: cat(:)
      type(hidden_effect) :: h(2)
      character(len=:), allocatable :: text
      character(len=64) :: size_text
      logical :: beyond
      integer :: ks, kb
      cat = effect_catalogue(20.0_dp)
      do ks = 1, size(cat)
         if (cat(ks)%name == 'softening') exit
      end do
      do kb = 1, size(cat)
         if (cat(kb)%name == 'backstress2') exit
      end do
      call hidden_size(cat(kb), [1290.0_dp, 200.0_dp], 1, 20.0_dp, 'ksi', size_text, beyond)
      call check(error, trim(size_text) == 'H3/gamma3 = 6.45E+00 ksi' .and. .not. beyond, &
                 'a second back stress by its saturation: '//trim(size_text))
      if (allocated(error)) return
      call hidden_size(cat(ks), [59.9_dp, 100.0_dp], 1, 20.0_dp, 'ksi', size_text, beyond)
      call check(error, beyond, 'a softening of a = 59.9 beyond its limit')
      if (allocated(error)) return
      h(1)%times = 1198.0_dp
      h(1)%beyond = .true.
      h(2)%times = 2.0_dp
      h(2)%test = 'tension at 1e-5 /s'
      h(2)%power = 0.39_dp
      text = missed_note([character(len=16) :: 'softening', 'drift'], [0.2_dp, 0.949_dp], h, 'these tests')
      call check(error, index(text, 'softening (power 0.20 there; not found with power 0.95 within '// &
                 'its physical limit)') > 0 .and. index(text, 'drift (power 0.94 there; found with '// &
                 'power 0.95 from 2.0 times it)') > 0, text)
   end subroutine test_missed_note

end module test_diagnose
