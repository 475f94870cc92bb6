!> Per-specimen diagnosis: how one specimen differs from its replicates. The constants are
!> fitted to the other tests (the replicates) alone; the specimen is predicted with them, and
!> each catalogue effect is then fitted to the specimen alone with the constants fixed (every
!> parameter of the effect belongs to this specimen: a global effect of the catalogue is
!> here one more property of this test). Each effect gets its magnitudes with 95 %
!> profile-likelihood intervals, the fall of BIC on the specimen's points and the share of
!> the specimen's structured gap it removes; the effects are ranked by BIC.
module usharp_diagnose_specimen
   use usharp_kinds, only: dp
   use usharp_lapack, only: mat_mul, svd
   use usharp_math, only: log_dp, exp_dp
   use usharp_error, only: error_type, fatal_error, stat_input
   use usharp_strings, only: str, real_str, report_line_len, add_line, csv_field
   use usharp_config, only: run_config
   use usharp_history, only: control_strain
   use usharp_input_test, only: name_len
   use usharp_model, only: constant_names
   use usharp_objective, only: fit_problem, setup_problem
   use usharp_experiment, only: experiment_type, fits_strain
   use usharp_effects, only: test_effects, effect_info, effect_catalogue, n_effects, &
                             effect_nparams, param_per_test, effects_of
   use usharp_effect_problem, only: effect_problem, new_effect_problem
   use usharp_levenberg, only: levenberg_marquardt
   use usharp_optimiser, only: optimum_type
   use usharp_identify, only: robust_covariance
   use usharp_regions, only: gap_se
   use usharp_sort, only: order_of
   use usharp_diagnose_options, only: diagnose_options, bic_margin, gap_z, corr_lag, correlated_ratio
   use usharp_diagnose_numerics, only: jacobian, pseudo_inverse, set_constants_at, softening_starts, lm_updates, &
                                       backstress2_starts, rate_effect_start, low_end_deltas, low_end_starts, &
                                       distinct_starts, bic_power, power_lambda, &
                                       tight_jacobian, sandwich_covariance, noise_variance, residual_noise, at_bound, &
                                       noise_correlation, &
                                       beyond_limit, limit_measures, lm_ftol, lm_itermax, test_sizes, &
                                       block_sums, at_box_end, below_resolved, resolved_share
   use usharp_diagnose_verdict, only: power_cells, missed_note, correlated_note
   use usharp_diagnose_types, only: most, hidden_effect, hidden_size, bound_list, unit_text, &
                                    params_bound_note, side_word, hardening_note, interval_text
   use usharp_diagnose_separate, only: finding_test
   use usharp_diagnose_profile, only: profile_interval, profile_result, open_beyond_estimate
   implicit none
   private

   public :: specimen_result, specimen_effect, specimen_run, specimen_report, specimen_index, specimen_verdict, &
             specimen_lead
   public :: specimen_csv, specimen_csv_header, own_measure
   public :: specimen_deviance, profiled_deviance, constants_directions, specimen_noncentrality

   !> The first line of specimen-<name>.csv (see specimen_csv)
   character(len=*), parameter :: specimen_csv_header = 'specimen,rank,effect,parameters,objective_after,'// &
      'dbic,gap_removed,significant,plausible,leads,parameter,value,lower_95,upper_95,lower_open,upper_open,'// &
      'unit,at_search_bound,chi_square_low_end,power_low_end'

   !> One effect fitted to the specimen
   type :: specimen_effect
      integer :: k = 0
      character(len=16) :: name = ''
      integer :: q = 0                                   !< its parameters
      real(dp) :: f_after = 0.0_dp                       !< specimen's objective with it
      real(dp) :: dbic = 0.0_dp                          !< BIC change on the specimen's points
      real(dp) :: removed = 0.0_dp                       !< share of the structured gap removed
      character(len=16), allocatable :: pname(:), punit(:)
      real(dp), allocatable :: p(:), p_lo(:), p_hi(:)    !< magnitudes, 95 % profile interval
      logical, allocatable :: lo_open(:), hi_open(:)     !< interval open at that end
      !> at an outer end of its search box: not determined by the data, its interval void
      integer, allocatable :: p_bound(:)                 !< -1, 1: at the lower, upper end
      logical :: plausible = .true.                      !< within the effect's physical limit
      !> Each free parameter's low end of its range (0: none; see below_resolved)
      real(dp), allocatable :: p_low(:)
      logical :: significant = .false.                   !< BIC falls by more than bic_margin
      !> Expected chi-square of the effect at the low end of its range on the specimen, and
      !> the power of the significance rule against it (negative: not computed)
      real(dp) :: lambda_low = 0.0_dp, power_low = -1.0_dp
      character(len=40) :: low_what = ''
      type(hidden_effect) :: hidden                      !< what of it the specimen could hide
      integer :: nevals = 0
      !> Its joint fit: the constants (log10) and each test's weighted sum of squares
      real(dp), allocatable :: xc(:), joint_tests(:)
      !> ... and its whole point (constants, then the effect's free parameters) and objective
      real(dp), allocatable :: xj(:)
      real(dp) :: fj = 0.0_dp
      !> Its intervals profiled with the constants refitted to all the tests at each point
      !> (the leading effect's), not held at the joint fit's
      logical :: profiled_joint = .false.
   end type specimen_effect

   !> The specimen against its replicates
   type :: specimen_result
      character(len=name_len) :: name = ''
      character(len=name_len), allocatable :: replicates(:)
      character(len=:), allocatable :: cnames(:)
      real(dp), allocatable :: c(:)          !< constants fitted to the replicates
      integer, allocatable :: c_bound(:)     !< of them, those at a search bound (see bound_list)
      real(dp) :: f_rep = 0.0_dp             !< their objective on the replicates
      !> each replicate's objective at their constants, in the fit's own measure of a test
      !> (Eq. 7: the test's objective, a mean square error; Eq. 13: its sum of squares per
      !> point): how well they fit themselves, against which the specimen's shows whether it
      !> stands out, whatever the number of points of each
      real(dp), allocatable :: rep_ms(:)
      logical :: per_point = .false.         !< the measure divides by the points (Eq. 13)
      integer :: m = 0                       !< the specimen's points
      real(dp) :: f0 = 0.0_dp                !< the specimen's objective, predicted
      real(dp) :: noise = 0.0_dp             !< the part of it the noise explains
      !> of noise, the part the constants' own uncertainty explains (their covariance from
      !> the replicates' noise, carried to the specimen)
      real(dp) :: pred = 0.0_dp
      real(dp) :: gap = 0.0_dp               !< structured gap: f0 - noise
      !> what a gap must exceed to be more than noise: gap_z standard errors of the one
      !> noise alone leaves (gap_se, as the held-out diagnosis's floors)
      real(dp) :: floor = 0.0_dp
      real(dp) :: noise_sd = 0.0_dp          !< response unit
      !> its noise sd from second differences corr_lag samples apart over that from
      !> neighbours (noise_correlation: 1 for independent noise)
      real(dp) :: noise_corr = 0.0_dp
      character(len=32) :: unit = ''
      character(len=8) :: stress_unit = ''   !< the model's stress unit
      type(specimen_effect), allocatable :: effects(:)   !< ranked by BIC
      !> Without an effect, the constants fitted to the replicates and the specimen together:
      !> the specimen's objective then (what no constants can take up of its prediction's
      !> misfit), and the objective of each test (the problem's order)
      real(dp) :: f_joint = -1.0_dp
      !> Each test's weight in the joint fits: n_i over its mean square in the first joint
      !> fit (squared, the factor on its residuals), and each test's weighted sum of
      !> squares in the joint fit without an effect
      real(dp), allocatable :: joint_weight(:), joint_tests(:)
      integer :: nevals = 0
      integer :: nevals_rep = 0              !< of them, simulations of the replicates' set
      !> The specimen's residual covariance s diag(nv) + Jc C Jc' (s profiled; C the constants'
      !> covariance from the replicates, Jc the specimen's residuals in them): its noise
      !> variances nv, an orthonormal basis w of the directions diag(nv)^-1/2 Jc C^1/2 spans
      !> and their squared singular values sig2 (none when the constants are given)
      real(dp), allocatable :: nv(:), w(:, :), sig2(:)
      !> The effect every test carries with the constants, as the report names it ('': none)
      character(len=:), allocatable :: carried
      !> What the verdict calls the replicates (unallocated: 'its replicates')
      character(len=:), allocatable :: peers
   end type specimen_result

contains

   !> Index of the test named name in cfg, 0 when there is none
   pure integer function specimen_index(cfg, name) result(k)
      type(run_config), intent(in) :: cfg
      character(len=*), intent(in) :: name
      integer :: i
      k = 0
      do i = 1, size(cfg%tests)
         if (cfg%tests(i)%name == trim(name)) k = i
      end do
   end function specimen_index

   !> Diagnose test ispec of cfg against the others: constants fitted to them from cfg's
   !> (refit_constants false: cfg's constants as they are), then each of opts's effects
   !> fitted to the specimen alone
   subroutine specimen_run(cfg, ispec, opts, refit_constants, sr, error, experiments, replicates, carried_k, &
                           carried_p, carried_free, carried_text, peers)
      type(run_config), intent(in) :: cfg
      integer, intent(in) :: ispec
      type(diagnose_options), intent(in) :: opts
      logical, intent(in) :: refit_constants
      type(specimen_result), intent(out) :: sr
      type(error_type), allocatable, intent(out) :: error
      type(experiment_type), intent(in), optional :: experiments(:)
      !> The replicates (indices into cfg's tests; absent: every other test)
      integer, intent(in), optional :: replicates(:)
      !> A global catalogue effect every test carries with cfg's constants, the specimen's
      !> own fitted on top of it (an effect fitted to the replicates with those constants,
      !> see held_own in usharp_diagnose; absent: none): its parameters (physical units),
      !> which of them were fitted (their uncertainty, with the constants', is the
      !> replicates' to give), and how the report names it
      integer, intent(in), optional :: carried_k
      real(dp), intent(in), optional :: carried_p(:)
      logical, intent(in), optional :: carried_free(:)
      character(len=*), intent(in), optional :: carried_text
      !> What the verdict calls the replicates (absent: 'its replicates')
      character(len=*), intent(in), optional :: peers
      type(fit_problem) :: prob
      type(effect_problem) :: ep, es, ej0, er
      type(optimum_type) :: opt, oj0
      real(dp), allocatable :: x_rep(:)
      integer, allocatable :: alltests(:), npts(:)
      type(test_effects) :: base, base0
      type(test_effects), allocatable :: eff_all(:)
      type(effect_problem) :: ec
      integer :: kc
      integer, allocatable :: kinds(:)
      type(effect_info) :: cat(n_effects), own(n_effects)
      real(dp), allocatable :: lo(:), hi(:), r0(:), dbic(:), rr(:), jc(:, :), cov(:, :)
      real(dp), allocatable :: ysim(:), rrep(:)
      type(specimen_effect), allocatable :: all(:)
      integer, allocatable :: reps(:)
      integer :: i, nt, j, lead
      real(dp) :: peak, speak, dev0, s0
      logical :: ok
      nt = size(cfg%tests)
      if (ispec < 1 .or. ispec > nt .or. nt < 2) then
         call fatal_error(error, cfg%path//': &diagnose: specimen: a per-specimen diagnosis needs '// &
            'the specimen and at least one replicate', stat_input)
         return
      end if
      call setup_problem(cfg, prob, error, experiments)
      if (allocated(error)) return
      reps = pack([(i, i=1, nt)], [(i, i=1, nt)] /= ispec)
      if (present(replicates)) reps = pack(replicates, replicates /= ispec)
      sr%name = cfg%tests(ispec)%name
      allocate (sr%replicates(size(reps)))
      do i = 1, size(reps)
         sr%replicates(i) = cfg%tests(reps(i))%name
      end do
      peak = maxval([(prob%targets(i)%y_ex_max, i=1, nt)])
      cat = effect_catalogue(peak)
      ! The specimen's own peak stress, which its effects' physical limits are set against
      if (fits_strain(prob%cfg%tests(ispec))) then
         speak = maxval(abs(prob%cfg%tests(ispec)%hist%v))
      else
         speak = prob%targets(ispec)%y_ex_max
      end if
      own = effect_catalogue(speak)
      base%dlnE_dT = opts%dlnE_dT
      base%gamma3 = opts%gamma3
      base0 = base
      kc = 0
      if (present(carried_k) .and. present(carried_p) .and. present(carried_free)) kc = carried_k
      if (kc > 0) then
         eff_all = effects_of(kc, carried_p, nt, base0)
         base = eff_all(ispec)
      end if
      if (present(carried_text)) sr%carried = carried_text
      if (present(peers)) sr%peers = peers
      ! The constants of the replicates
      call new_effect_problem(prob, reps, 0, base, peak, ep)
      if (refit_constants) then
         call ep%bounds(lo, hi)
         call levenberg_marquardt(ep, ep%start(), lo, hi, cfg%fit%fd_step, 1.0e-9_dp, 100, &
                                  opts%max_evals, opt, error, updates=lm_updates)
         if (allocated(error)) return
         sr%nevals = sr%nevals + opt%nevals
         sr%nevals_rep = opt%nevals
         call set_constants_at(prob, opt%x)
         sr%f_rep = opt%f
         sr%c_bound = at_bound(opt%x, lo, hi)
         call replicates_covariance(ep, opt%x)
      else
         call ep%eval(ep%start(), sr%f_rep, error)
         if (allocated(error)) return
         ! Given constants and a carried effect fitted to the replicates: the covariance of
         ! both from the replicates' noise at that point, as their own fit gives it above
         if (kc > 0) then
            call carried_problem(reps, ec)
            call replicates_covariance(ec, ec%start())
         end if
      end if
      sr%cnames = constant_names(prob%cfg%model, prob%idx)
      sr%c = [(prob%cfg%model%get_constant(prob%idx(j)), j=1, size(prob%idx))]
      ! Each replicate's objective per point at these constants
      call new_effect_problem(prob, reps, 0, base, peak, er, free_constants=.false.)
      allocate (rrep(er%nres()))
      call er%residual_at(er%start(), rrep, ok)
      sr%nevals = sr%nevals + 1
      sr%per_point = prob%cfg%fit%objective /= 'eq7'
      if (ok) then
         sr%rep_ms = block_sums(test_sizes(prob, reps), rrep)
         if (sr%per_point) sr%rep_ms = sr%rep_ms/real(test_sizes(prob, reps), dp)
      end if
      ! The specimen predicted, and its noise part
      call new_effect_problem(prob, [ispec], 0, base, peak, ep, free_constants=.false.)
      sr%m = ep%nres()
      allocate (r0(sr%m), ysim(sr%m))
      call ep%residual_at(ep%start(), r0, ok, ysim)
      if (.not. ok) then
         call fatal_error(error, "the replicates' constants fail to simulate specimen '"// &
            trim(sr%name)//"'")
         return
      end if
      sr%f0 = sum(r0**2)
      sr%noise_sd = sum(residual_noise(prob, [ispec], ysim))
      sr%noise_corr = sum(noise_correlation(prob, [ispec], ysim))
      sr%nv = noise_variance(prob, [ispec], [sr%noise_sd])
      ! (data without noise leave no covariance to weigh by)
      if (allocated(cov) .and. any(sr%nv > 0.0_dp)) then
         ! The specimen's residuals in the constants (the same packing as the replicates')
         if (kc > 0) then
            call carried_problem([ispec], es)
         else
            call new_effect_problem(prob, [ispec], 0, base, peak, es)
         end if
         call tight_jacobian(es, es%start(), cfg%fit%fd_step, rr, jc, ok)
         sr%nevals = sr%nevals + size(jc, 2) + 1
         if (ok) call constants_directions(sr, jc, cov)
      end if
      ! The prediction's -2 log-likelihood, against which each effect's is set
      if (allocated(sr%w)) call profiled_deviance(sr, r0, dev0, s0)
      sr%noise = sum(sr%nv) + sr%pred
      sr%gap = max(sr%f0 - sr%noise, 0.0_dp)
      sr%floor = gap_z*gap_se(sr%nv, spread(1, 1, sr%m), [sr%m], [.true.])
      sr%stress_unit = prob%cfg%units
      sr%unit = merge('strain (-)     ', 'stress ('//prob%cfg%units//')   ', &
                      fits_strain(prob%cfg%tests(ispec)))
      ! The specimen beside its replicates, no effect: the constants fitted to all of them.
      ! Each effect's BIC is set against this fit, the effect's own refitting the constants
      ! too, so that what the replicates leave open of the constants is open to both (the
      ! nonlinear form of the covariance above, which a specimen predicted from replicates
      ! that hardly bound it overstates: a cyclic test predicted from a relaxation test alone
      ! took a second back stress, BIC -263, for the constants' own error)
      if (refit_constants) then
         alltests = [(i, i=1, nt)]
         npts = test_sizes(prob, alltests)
         call new_effect_problem(prob, alltests, 0, base, peak, ej0)
         call ej0%bounds(lo, hi)
         x_rep = ej0%start()
         call joint_fit(x_rep, error)
         if (allocated(error)) return
         ! Then each test weighted by its number of points over its mean square there, and
         ! fitted again: a test counts by its points and its own scatter (noise and misfit),
         ! as each test's residuals of a variance of their own do in the held-out BIC. With
         ! every test counting alike, a specimen three times noisier than its replicates, or
         ! one of 17 points beside 12800, took an effect (BIC -39, -168) that only moved the
         ! constants between the tests.
         sr%joint_weight = real(npts, dp)/max(sr%joint_tests, tiny(1.0_dp))
         ej0%test_scale = sqrt(sr%joint_weight)
         x_rep = oj0%x  ! (a copy: joint_fit sets oj0)
         call joint_fit(x_rep, error)
         x_rep = ej0%start()
         if (allocated(error)) return
      end if
      ! Each effect on the specimen alone (not the carried effect's kind, whose parameters
      ! would replace the carried ones, not add to them)
      kinds = pack(opts%effects, opts%effects /= kc)
      allocate (all(size(kinds)))
      do j = 1, size(kinds)
         call fit_effect(kinds(j), all(j), error)
         if (allocated(error)) return
         sr%nevals = sr%nevals + all(j)%nevals
      end do
      if (refit_constants) call joint_restart(error)
      if (allocated(error)) return
      dbic = all%dbic
      sr%effects = all(order_of(dbic))
      if (refit_constants) then
         call specimen_lead(sr, lead, j)
         if (lead > 0) call joint_profile(sr%effects(lead), error)
         if (allocated(error)) return
      end if
   contains
      !> What the replicates leave open of the free parameters of ek (the constants, and a
      !> carried effect's) at x: their covariance from the replicates' noise, the sandwich
      !> at a tight tolerance (cov; unallocated where a point fails to simulate)
      subroutine replicates_covariance(ek, x)
         type(effect_problem), intent(inout) :: ek
         real(dp), intent(in) :: x(:)
         real(dp), allocatable :: rr(:), jr(:, :), yfit(:), nvr(:)
         logical :: ok
         call tight_jacobian(ek, x, cfg%fit%fd_step, rr, jr, ok)
         sr%nevals = sr%nevals + size(jr, 2) + 1
         if (ok) then
            ! (their noise from their residuals at this point, as the specimen's below)
            allocate (yfit(ek%nres()))
            call ek%residual_at(x, rr, ok, yfit)
            sr%nevals = sr%nevals + 1
         end if
         if (ok) then
            nvr = noise_variance(prob, reps, residual_noise(prob, reps, yfit))
            cov = sandwich_covariance(jr, nvr)
         end if
      end subroutine replicates_covariance

      !> The tests `tests` with the carried effect kc, the constants and its fitted
      !> parameters free (the layout the covariance is in)
      subroutine carried_problem(tests, ek)
         integer, intent(in) :: tests(:)
         type(effect_problem), intent(out) :: ek
         call new_effect_problem(prob, tests, kc, base0, peak, ek, p0=carried_p)
         ek%pfree = carried_free .and. ek%pacts
      end subroutine carried_problem

      !> The joint fit without an effect from x: oj0, and what follows of it in sr
      subroutine joint_fit(x, error)
         real(dp), intent(in) :: x(:)
         type(error_type), allocatable, intent(out) :: error
         real(dp), allocatable :: rj(:)
         logical :: ok
         call levenberg_marquardt(ej0, x, lo, hi, cfg%fit%fd_step, lm_ftol, lm_itermax, &
                                  opts%max_evals, oj0, error, updates=lm_updates)
         if (allocated(error)) return
         sr%nevals = sr%nevals + oj0%nevals
         allocate (rj(sum(npts)))
         call ej0%residual_at(oj0%x, rj, ok)
         if (.not. ok) then
            call fatal_error(error, "the constants fitted to the replicates and specimen '"// &
               trim(sr%name)//"' together fail to simulate them")
            return
         end if
         sr%joint_tests = block_sums(npts, rj)
         sr%f_joint = sr%joint_tests(ispec)
         if (allocated(sr%joint_weight)) sr%f_joint = sr%f_joint/sr%joint_weight(ispec)
         ! What no constants take up of the specimen, beyond its noise
         sr%gap = max(sr%f_joint - sum(sr%nv), 0.0_dp)
      end subroutine joint_fit

      !> An effect's joint fit whose constants, with the effect off, fit the tests better
      !> than the joint fit without it shows that fit stopped short: it runs again from
      !> there, and every BIC change is taken against it (on clean data a compliance of BIC
      !> -11.0 was against a fit without an effect that a fit of the tests improves on)
      subroutine joint_restart(error)
         type(error_type), allocatable, intent(out) :: error
         real(dp), allocatable :: rj(:)
         real(dp) :: f, fbest
         integer :: j, jbest
         logical :: ok
         allocate (rj(sum(npts)))
         fbest = oj0%f
         jbest = 0
         do j = 1, size(all)
            if (.not. allocated(all(j)%xc)) cycle
            call ej0%residual_at(all(j)%xc, rj, ok)
            sr%nevals = sr%nevals + 1
            if (.not. ok) cycle
            f = sum(rj**2)
            if (f < fbest) then
               fbest = f
               jbest = j
            end if
         end do
         ! (beyond a last-digit difference of the stopping rule)
         if (jbest == 0 .or. fbest >= oj0%f*(1.0_dp - 1.0e-9_dp)) return
         call joint_fit(all(jbest)%xc, error)
         if (allocated(error)) return
         do j = 1, size(all)
            if (.not. allocated(all(j)%joint_tests)) cycle
            all(j)%dbic = sum(all(j)%joint_tests - sr%joint_tests) + all(j)%q*log_dp(real(sr%m, dp))
            all(j)%significant = all(j)%dbic < -bic_margin
            all(j)%removed = gap_share(sr%f_joint, all(j)%f_after)
         end do
      end subroutine joint_restart

      !> Effect k's parameters of the specimen fitted with the constants fixed; Wald and then
      !> profile intervals
      subroutine fit_effect(k, se_out, error)
         integer, intent(in) :: k
         type(specimen_effect), intent(out) :: se_out
         type(error_type), allocatable, intent(out) :: error
         type(effect_problem) :: ek, ej
         type(optimum_type) :: o, o1, oj, x_low
         real(dp), allocatable :: xj(:, :), rjk(:), ptj(:)
         type(profile_result) :: pr
         integer :: pass
         logical :: lower
         real(dp), allocatable :: lo(:), hi(:), r(:), jac(:, :), cov(:, :), naive(:, :), se(:), p(:)
         real(dp), allocatable :: starts(:, :), d(:, :), xs(:, :)
         real(dp) :: scale, reach, saturation
         integer, allocatable :: grp(:)
         ! Figures and intervals again from a lower point that a profile met, at most twice
         integer, parameter :: max_passes = 3
         integer :: jj, g, np
         logical :: okj
         se_out%k = k
         se_out%name = cat(k)%name
         call specimen_problem(k, ek)
         np = size(ek%p0)
         se_out%q = count(ek%pfree)
         call ek%bounds(lo, hi)
         ! An effect from its zero and from plus and minus its low end on the specimen
         ! (low_end_starts), the lowest end point kept: a temperature offset of -5 K on one
         ! specimen, refitted from zero alone, stayed at -0.004 K and left the specimen to
         ! scatter
         d = low_end_deltas(ek, cat(k), [ispec])
         starts = low_end_starts(ek%p0, d)
         ! The second back stress from saturations and rates apart (backstress2_starts)
         if (k == 8) starts = backstress2_starts(peak, opts%gamma3)
         ! The saturating softening of either sign at three rates (the first is the zero start)
         if (k == 7) starts = softening_starts(cat(k))
         se_out%nevals = 0
         call low_end_power(ek, se_out)
         call distinct_starts(ek, starts, lo, hi, xs)
         do jj = 1, size(xs, 2)
            call levenberg_marquardt(ek, xs(:, jj), lo, hi, 1.0e-3_dp, 1.0e-10_dp, 100, opts%max_evals, &
                                     o1, error, updates=lm_updates)
            if (allocated(error)) return
            se_out%nevals = se_out%nevals + o1%nevals
            call keep_lower(o, o1, jj == 1)
         end do
         if (refit_constants) then
            ! The effect on the specimen with the constants refitted to all the tests: from
            ! the joint fit without it (the effect off), and from the replicates' constants
            ! with the effect as fitted above; BIC against the joint fit without it, each
            ! test's residuals of a variance of their own (deviance_change)
            call joint_problem(ek, ej)
            call ej%bounds(lo, hi)
            allocate (xj(size(x_rep) + size(o%x), 2))
            xj(:, 1) = [x_rep, o%x]
            xj(:, 2) = [oj0%x, min(max(0.0_dp*o%x, lo(size(x_rep) + 1:)), hi(size(x_rep) + 1:))]
            do jj = 1, 2
               call levenberg_marquardt(ej, xj(:, jj), lo, hi, cfg%fit%fd_step, lm_ftol, lm_itermax, &
                                        opts%max_evals, o1, error, updates=lm_updates)
               if (allocated(error)) return
               se_out%nevals = se_out%nevals + o1%nevals
               call keep_lower(oj, o1, jj == 1)
               ! (the second start, the joint fit's own point with the effect off, only
               ! where the first ended above that fit: it cannot end above it)
               if (oj%f <= oj0%f) exit
            end do
            allocate (rjk(sum(npts)))
            call ej%residual_at(oj%x, rjk, okj)
            if (okj) then
               ptj = block_sums(npts, rjk)
               se_out%joint_tests = ptj
               se_out%xc = oj%x(:size(x_rep))
               se_out%xj = oj%x
               se_out%fj = oj%f
               ! The weighted sums of squares' change: each test's variance held at its
               ! weight's, so the fall of chi-square
               se_out%dbic = sum(ptj - sr%joint_tests) + se_out%q*log_dp(real(sr%m, dp))
               ! The specimen alone from here on: its objective, magnitudes and intervals at
               ! the joint fit's constants
               call set_constants_at(ek%prob, oj%x(:size(x_rep)))
               ! (the joint fit's stopping rule is on the objective of all the tests: the
               ! effect's parameters are finished on the specimen's own, where the profile
               ! starts)
               call ek%bounds(lo, hi)
               call levenberg_marquardt(ek, oj%x(size(x_rep) + 1:), lo, hi, 1.0e-3_dp, 1.0e-10_dp, 100, &
                                        opts%max_evals, o, error, updates=lm_updates)
               if (allocated(error)) return
               se_out%nevals = se_out%nevals + o%nevals
            else
               se_out%dbic = huge(1.0_dp)
            end if
         end if
         ! The figures at o, and again (max_passes) from a lower point that a profile met
         ! (o was not the optimum: the intervals are about that point, and so is the rest)
         do pass = 1, max_passes
            if (pass > 1) deallocate (se, grp, se_out%p_lo, se_out%p_hi, se_out%lo_open, &
                                      se_out%hi_open, se_out%pname, se_out%punit)
            lower = .false.
            x_low%f = o%f
            se_out%f_after = o%f
            se_out%removed = gap_share(merge(sr%f_joint, sr%f0, refit_constants), o%f)
            call jacobian(ek, o%x, 1.0e-3_dp, r, jac, okj)
            if (.not. refit_constants) then
               ! BIC in the residual's covariance: what the given constants leave open is not
               ! the specimen's
               if (okj .and. size(r) == sr%m .and. allocated(sr%w)) then
                  se_out%dbic = specimen_deviance(sr, r) - dev0 + se_out%q*log_dp(real(sr%m, dp))
               else
                  se_out%dbic = sr%m*log_dp(max(o%f, tiny(1.0_dp))/sr%f0) + se_out%q*log_dp(real(sr%m, dp))
               end if
            end if
            se_out%significant = se_out%dbic < -bic_margin
            naive = pseudo_inverse(mat_mul(transpose(jac), jac))
            cov = robust_covariance(jac, r, naive)
            allocate (se(size(o%x)))
            do jj = 1, size(o%x)
               se(jj) = sqrt(max(cov(jj, jj), 0.0_dp))
            end do
            p = pack(o%x*pack(ek%pscale, ek%pfree), .true.)
            se_out%p = p
            allocate (se_out%p_lo(size(p)), se_out%p_hi(size(p)), se_out%lo_open(size(p)), &
                      se_out%hi_open(size(p)), se_out%pname(size(p)), se_out%punit(size(p)))
            allocate (grp(size(p)))
            g = 0
            do jj = 1, np
               if (.not. ek%pfree(jj)) cycle
               g = g + 1
               grp(g) = merge((jj - 1)/nt + 1, jj, cat(k)%sharing == param_per_test)
               se_out%pname(g) = cat(k)%pname(grp(g))
               se_out%punit(g) = cat(k)%punit(grp(g))
               ! The rise of the objective at the 95 % ends: the sandwich over the naive variance
               scale = o%f/max(sr%m - se_out%q, 1)
               if (naive(g, g) > 0.0_dp .and. cov(g, g) > 0.0_dp) scale = cov(g, g)/naive(g, g)
               call profile_interval(ek, o%x, o%f, g, lo, hi, 1.0e-3_dp, se(g), scale, &
                                     ek%pnonneg(jj) .and. o%x(g) > 0.0_dp, opts%max_evals, pr, error)
               if (allocated(error)) return
               se_out%nevals = se_out%nevals + pr%nevals
               call take_interval(se_out, g, pr, ek%pscale(jj))
               if (pr%f_centre < x_low%f) then
                  x_low%x = pr%x_centre
                  x_low%f = pr%f_centre
                  lower = .true.
               end if
            end do
            if (.not. lower .or. pass == max_passes) exit
            o%x = x_low%x
            o%f = x_low%f
         end do
         ! (profiles that still met lower points in the last pass: intervals about such a
         ! point may leave out the estimate)
         call open_beyond_estimate(se_out%p, se_out%p_lo, se_out%p_hi, se_out%lo_open, se_out%hi_open)
         ! A parameter at an outer end of its search box (dD0/D0 of 52 [52.1, 52.3], 130 times
         ! its limit, a profile pinned there) is not measured by the data
         call ek%bounds(lo, hi)
         se_out%p_bound = at_box_end(o%x, lo, hi)
         ! Beyond its physical limit only as the held-out diagnosis judges it
         ! (against the specimen's own peak: a second back stress of 151 MPa passed beside the
         ! largest peak of the set, 175 MPa, on a specimen peaking at 113 MPa)
         call limit_measures(own(k), ek, o%x, p, speak, reach, saturation)
         se_out%plausible = beyond_limit(own(k), grp, p, se_out%p_lo, se_out%p_hi, &
                                         se_out%lo_open .or. se_out%hi_open, reach, saturation) <= 1.0_dp
         ! The low ends its intervals are set against, d of the starts (a second back
         ! stress's is one of its saturation, which no interval here bounds)
         allocate (se_out%p_low(size(p)))
         se_out%p_low = 0.0_dp
         if (size(d, 2) > 0 .and. cat(k)%name /= 'backstress2') se_out%p_low = pack(maxval(abs(d), 2), ek%pfree)
      end subroutine fit_effect

      !> Effect k on the specimen alone, the constants fixed: per-test parameters only the
      !> specimen's own free; the second back stress and the softening from their starts
      subroutine specimen_problem(k, ek)
         integer, intent(in) :: k
         type(effect_problem), intent(out) :: ek
         integer :: jj
         call new_effect_problem(prob, [ispec], k, base, peak, ek, free_constants=.false.)
         do jj = 1, size(ek%p0)
            if (cat(k)%sharing == param_per_test) ek%pfree(jj) = mod(jj - 1, nt) + 1 == ispec .and. ek%pacts(jj)
         end do
         if (k == 7 .or. k == 8) ek%p0 = rate_effect_start(cat(k), k, peak, opts%gamma3)
      end subroutine specimen_problem

      !> The same effect on the specimen beside its replicates, the constants free and each
      !> test weighted as in the joint fits
      subroutine joint_problem(ek, ej)
         type(effect_problem), intent(in) :: ek
         type(effect_problem), intent(out) :: ej
         call new_effect_problem(prob, alltests, ek%k, base, peak, ej, p0=ek%p0)
         ej%pfree = ek%pfree
         ej%effect_test = ispec
         ej%test_scale = sqrt(sr%joint_weight)
      end subroutine joint_problem

      !> The leading effect's 95 % intervals profiled in the joint problem: at each trial
      !> value the constants (and its other parameters) refitted to the specimen and its
      !> replicates together, the rise of their weighted sum of squares set against chi-square
      !> (each test's residuals scaled to a variance of about one, as the BIC takes them).
      !> With the constants held at the joint fit's, 17 of 20 intervals of drifts at the top
      !> of their range held the injected drift.
      subroutine joint_profile(e, error)
         type(specimen_effect), intent(inout) :: e
         type(error_type), allocatable, intent(out) :: error
         type(effect_problem) :: ek, ej
         type(profile_result) :: pr
         real(dp), allocatable :: lo(:), hi(:)
         real(dp) :: se0
         integer :: g, jj, nc
         if (.not. allocated(e%xj)) return
         call specimen_problem(e%k, ek)
         call joint_problem(ek, ej)
         call ej%bounds(lo, hi)
         nc = size(e%xj) - e%q
         g = 0
         do jj = 1, size(ek%p0)
            if (.not. ek%pfree(jj)) cycle
            g = g + 1
            ! (the first step: a quarter of the held interval's half width)
            se0 = max(0.125_dp*(e%p_hi(g) - e%p_lo(g))/ek%pscale(jj), 1.0e-6_dp)
            call profile_interval(ej, e%xj, e%fj, nc + g, lo, hi, cfg%fit%fd_step, se0, 1.0_dp, &
                                  ek%pnonneg(jj) .and. e%xj(nc + g) > 0.0_dp, opts%max_evals, pr, error)
            if (allocated(error)) return
            sr%nevals = sr%nevals + pr%nevals
            call take_interval(e, g, pr, ek%pscale(jj))
         end do
         e%profiled_joint = .true.
      end subroutine joint_profile

      !> Parameter g's interval of effect e from its profile pr (x units times pscale)
      subroutine take_interval(e, g, pr, pscale)
         type(specimen_effect), intent(inout) :: e
         integer, intent(in) :: g
         type(profile_result), intent(in) :: pr
         real(dp), intent(in) :: pscale
         e%p_lo(g) = pr%lo*pscale
         e%p_hi(g) = pr%hi*pscale
         e%lo_open(g) = pr%lo_open
         e%hi_open(g) = pr%hi_open
      end subroutine take_interval

      !> The share of the specimen's structured gap that going from objective f_from to
      !> f_to removes (beyond the whole gap only by the noise: all of it)
      pure real(dp) function gap_share(f_from, f_to) result(share)
         real(dp), intent(in) :: f_from, f_to
         share = 0.0_dp
         if (sr%gap > 0.0_dp) share = min((f_from - f_to)/sr%gap, 1.0_dp)
      end function gap_share

      !> best = new when first, or when new ends lower
      subroutine keep_lower(best, new, first)
         type(optimum_type), intent(inout) :: best
         type(optimum_type), intent(in) :: new
         logical, intent(in) :: first
         if (first) then
            best = new
         else if (new%f < best%f) then
            best = new
         end if
      end subroutine keep_lower

      !> The power of the significance rule against effect ek%k at the low end of its range
      !> on the specimen (low_end_deltas, bic_power): its signal simulated there against the
      !> prediction r0, in the covariance the BIC change is taken in (see
      !> specimen_noncentrality; without it, over the prediction's mean square)
      subroutine low_end_power(ek, se_out)
         type(effect_problem), intent(inout) :: ek
         type(specimen_effect), intent(inout) :: se_out
         real(dp), allocatable :: d(:, :), pz(:)
         real(dp) :: lambda
         integer :: g, gmin
         logical :: okr
         se_out%low_what = cat(ek%k)%low_what
         ! The effect off: every parameter with a low end at zero; a held rate (softening,
         ! second back stress: a global parameter without one) stays at its start
         pz = 0.0_dp*ek%p0
         if (cat(ek%k)%sharing /= param_per_test) then
            where (cat(ek%k)%low(:size(pz)) <= 0.0_dp) pz = ek%p0
         end if
         d = low_end_deltas(ek, cat(ek%k), [ispec])
         if (sr%f0 <= 0.0_dp .or. size(d, 2) == 0) return
         se_out%lambda_low = huge(1.0_dp)
         gmin = 1
         do g = 1, size(d, 2)
            call signal_at(ek, pz + d(:, g), se_out, lambda, okr)
            if (.not. okr) return
            if (lambda < se_out%lambda_low) gmin = g
            se_out%lambda_low = min(se_out%lambda_low, lambda)
         end do
         se_out%power_low = bic_power(se_out%lambda_low, se_out%q, sr%m)
         if (se_out%power_low < 0.95_dp) call hidden_bound(ek, pz, d(:, gmin), se_out)
      end subroutine low_end_power

      !> The chi-square of effect ek%k's signal on the specimen at parameters p (all tests',
      !> physical), as low_end_power takes it
      subroutine signal_at(ek, p, se_out, lambda, ok)
         type(effect_problem), intent(inout) :: ek
         real(dp), intent(in) :: p(:)
         type(specimen_effect), intent(inout) :: se_out
         real(dp), intent(out) :: lambda
         logical, intent(out) :: ok
         real(dp), allocatable :: r(:)
         allocate (r(ek%nres()))
         call ek%residual_at(pack(p/ek%pscale, ek%pfree), r, ok)
         se_out%nevals = se_out%nevals + 1
         lambda = 0.0_dp
         if (.not. ok) return
         if (allocated(sr%w)) then
            lambda = specimen_noncentrality(sr, r - r0, s0)
         else
            lambda = sum((r - r0)**2)/(sr%f0/sr%m)
         end if
      end subroutine signal_at

      !> How much of the effect the specimen could hide: the multiple of its low end (along
      !> the weakest of them, d) at which the rule's power is 0.95, the signal's chi-square
      !> simulated there (from its low end's, as if linear in the magnitude, then corrected
      !> twice); and the candidate test that would find that much
      subroutine hidden_bound(ek, pz, d, se_out)
         type(effect_problem), intent(inout) :: ek
         real(dp), intent(in) :: pz(:), d(:)
         type(specimen_effect), intent(inout) :: se_out
         real(dp), parameter :: most_times = 1.0e4_dp
         real(dp) :: target, times, lambda, emax
         real(dp), allocatable :: p(:), p1(:)
         integer :: it, j, g
         logical :: ok
         target = power_lambda(0.95_dp, se_out%q, sr%m)
         lambda = se_out%lambda_low
         times = 1.0_dp
         do it = 1, 3
            if (lambda <= 0.0_dp) return
            times = min(times*sqrt(target/lambda), most_times)
            if (it == 3) exit
            call signal_at(ek, pz + times*d, se_out, lambda, ok)
            if (.not. ok) return
         end do
         se_out%hidden%times = times
         p = pz + times*d
         ! One test's parameters: the specimen's own of a per-test effect
         if (cat(ek%k)%sharing == param_per_test) then
            p1 = [(p((g - 1)*nt + ispec), g=1, cat(ek%k)%nparam)]
         else
            p1 = p(:effect_nparams(cat(ek%k), 1))
         end if
         j = maxloc(abs(d), 1)
         g = merge((j - 1)/nt + 1, j, cat(ek%k)%sharing == param_per_test)
         ! (against the specimen's own limits, as its fitted effects are judged)
         call hidden_size(own(ek%k), p1, g, speak, prob%cfg%units, se_out%hidden%magnitude, &
                          se_out%hidden%beyond)
         emax = 0.005_dp
         associate (h => prob%cfg%tests(ispec)%hist)
            if (h%control == control_strain) emax = maxval(abs(h%v))
         end associate
         call finding_test(ek%prob%cfg%model, ek%k, p1, base, ek%prob%cfg%solver, emax, &
                           sr%noise_sd/max(prob%targets(ispec)%y_ex_max, tiny(1.0_dp)), se_out%q, &
                           se_out%hidden%test, se_out%hidden%power, se_out%nevals, &
                           prob%cfg%tests(ispec)%temperature)
      end subroutine hidden_bound
   end subroutine specimen_run

   !> The directions of the specimen's residual covariance that the constants' uncertainty
   !> adds (see specimen_result): with C = V diag(c) V', from Jc V diag(c)^1/2 (see
   !> spread_directions)
   pure subroutine constants_directions(sr, jc, cov)
      type(specimen_result), intent(inout) :: sr
      real(dp), intent(in) :: jc(:, :), cov(:, :)
      real(dp), allocatable :: c(:), v(:, :)
      integer :: j, info
      allocate (c(size(cov, 1)), v(size(cov, 1), size(cov, 1)))
      call svd(cov, c, v, info)
      if (info /= 0) return
      do j = 1, size(c)
         v(:, j) = v(:, j)*sqrt(max(c(j), 0.0_dp))
      end do
      call spread_directions(sr, mat_mul(jc, v))
   end subroutine constants_directions

   !> The same from d, whose d d' is the residuals' covariance from the constants (Jc V
   !> diag(c)^1/2, or its secant form): Z = diag(nv)^-1/2 d = W diag(sig) U', kept where sig
   !> is above 1e-8 of its largest; sr%pred the trace of d d'
   pure subroutine spread_directions(sr, d)
      type(specimen_result), intent(inout) :: sr
      real(dp), intent(in) :: d(:, :)
      real(dp), allocatable :: z(:, :), sz(:), vz(:, :)
      integer :: j, k, info
      sr%pred = sum(d**2)
      if (size(d, 2) == 0) return
      z = d
      do j = 1, size(z, 2)
         z(:, j) = whitened(sr, z(:, j))
      end do
      allocate (sz(size(z, 2)), vz(size(z, 2), size(z, 2)))
      call svd(z, sz, vz, info)
      if (info /= 0) return
      k = count(sz > 1.0e-8_dp*maxval(sz))
      if (.not. maxval(sz) > 0.0_dp) k = 0
      sr%w = mat_mul(z, vz(:, :k))
      do j = 1, k
         sr%w(:, j) = sr%w(:, j)/sz(j)
      end do
      sr%sig2 = sz(:k)**2
   end subroutine spread_directions

   !> The specimen's residuals r as -2 log-likelihood (without constants) in the covariance
   !> s diag(nv) + Jc C Jc', minimised over the noise scale s: with x = diag(nv)^-1/2 r, its
   !> coordinates g = w'x and the rest p = |x - w g|**2, (m - k) ln s + sum ln(s + sig2) +
   !> p/s + sum g**2/(s + sig2) (no cancellation where the constants take up most of r).
   !> Without that covariance (k = 0) the minimum is m ln(|x|**2/m) + m, and a difference of
   !> two of them BIC's m ln(f1/f0)
   pure function specimen_deviance(sr, r) result(dev)
      type(specimen_result), intent(in) :: sr
      real(dp), intent(in) :: r(:)
      real(dp) :: dev
      real(dp) :: scale
      call profiled_deviance(sr, r, dev, scale)
   end function specimen_deviance

   !> specimen_deviance, and the noise scale s at its minimum
   pure subroutine profiled_deviance(sr, r, dev, scale)
      type(specimen_result), intent(in) :: sr
      real(dp), intent(in) :: r(:)
      real(dp), intent(out) :: dev, scale
      real(dp), allocatable :: x(:), g(:)
      real(dp) :: p, a, b, t1, t2, f1, f2
      real(dp), parameter :: golden = 0.6180339887498949_dp
      integer :: it, m
      m = count(sr%nv > 0.0_dp)
      x = whitened(sr, r)
      g = mat_mul(transpose(sr%w), x)
      p = sum((x - mat_mul(sr%w, g))**2)
      ! ln s between what the rest alone and the whole residual give, widened
      a = log_dp(max(p, tiny(1.0_dp)*m)/m) - 2.0_dp
      b = log_dp(max(sum(x**2), tiny(1.0_dp)*m)/m) + 2.0_dp
      t1 = b - golden*(b - a)
      t2 = a + golden*(b - a)
      f1 = at(t1)
      f2 = at(t2)
      do it = 1, 200
         if (b - a < 1.0e-12_dp) exit
         if (f1 <= f2) then
            b = t2
            t2 = t1
            f2 = f1
            t1 = b - golden*(b - a)
            f1 = at(t1)
         else
            a = t1
            t1 = t2
            f1 = f2
            t2 = a + golden*(b - a)
            f2 = at(t2)
         end if
      end do
      dev = min(f1, f2)
      scale = exp_dp(merge(t1, t2, f1 <= f2))
   contains
      pure real(dp) function at(t) result(f)
         real(dp), intent(in) :: t
         real(dp) :: s
         s = exp_dp(t)
         f = (m - size(g))*t + sum(log_dp(s + sr%sig2)) + p/s + sum(g**2/(s + sr%sig2))
      end function at
   end subroutine profiled_deviance

   !> The expected chi-square of a signal d in the specimen's residuals, d' S^-1 d in their
   !> covariance S = s diag(nv) + Jc C Jc' (see specimen_deviance) at noise scale s: with
   !> x = diag(nv)^-1/2 d and g = w'x, (|x|**2 - |g|**2)/s + sum g**2/(s + sig2). What the
   !> constants' uncertainty can take up of the signal does not count in full.
   pure real(dp) function specimen_noncentrality(sr, d, s) result(lambda)
      type(specimen_result), intent(in) :: sr
      real(dp), intent(in) :: d(:)
      real(dp), intent(in) :: s   !< noise scale, > 0
      real(dp), allocatable :: x(:), g(:)
      x = whitened(sr, d)
      g = mat_mul(transpose(sr%w), x)
      lambda = max(sum(x**2) - sum(g**2), 0.0_dp)/s + sum(g**2/(s + sr%sig2))
   end function specimen_noncentrality

   !> diag(nv)^-1/2 r on the points that carry a weight; 0 on those that do not (a weight of
   !> 0, as the relaxation weighting gives a test's first and last points, makes the
   !> residual 0 whatever the constants: no information, and no noise to divide by)
   pure function whitened(sr, r) result(x)
      type(specimen_result), intent(in) :: sr
      real(dp), intent(in) :: r(:)
      real(dp) :: x(size(r))
      x = 0.0_dp
      where (sr%nv > 0.0_dp) x = r/sqrt(sr%nv)
   end function whitened

   !> The effect the verdict names (lead, 0 when none) and the best by BIC of the significant
   !> and plausible ones (best): as in the held-out diagnosis, without strong evidence between
   !> them (BIC within bic_margin) the simplest leads, fewer parameters, then the lower BIC (a
   !> temperature offset of 5 K had been named scatter, two parameters, BIC 4 below it)
   pure subroutine specimen_lead(sr, lead, best)
      type(specimen_result), intent(in) :: sr
      integer, intent(out) :: lead, best
      integer :: j
      lead = 0
      do j = 1, size(sr%effects)
         if (lead == 0 .and. finding(sr%effects(j))) lead = j
      end do
      best = lead
      if (best == 0) return
      do j = best + 1, size(sr%effects)
         if (finding(sr%effects(j)) .and. sr%effects(j)%dbic < sr%effects(best)%dbic + bic_margin .and. &
             sr%effects(j)%q < sr%effects(lead)%q) lead = j
      end do
   end subroutine specimen_lead

   !> The specimen fitted by its replicates' constants no worse than the worst fitted of them
   !> fits itself (each per point): it does not stand out from them, and what an effect takes
   !> up of its gap is the model's gap at its range or rate, which the replicates share
   pure logical function typical(sr)
      type(specimen_result), intent(in) :: sr
      typical = .false.
      if (.not. allocated(sr%rep_ms) .or. sr%m < 1) return
      if (size(sr%rep_ms) == 0) return
      typical = own_measure(sr) <= maxval(sr%rep_ms)
   end function typical

   !> The specimen's objective at its replicates' constants in the measure of rep_ms
   pure real(dp) function own_measure(sr) result(f)
      type(specimen_result), intent(in) :: sr
      f = sr%f0
      if (sr%per_point) f = sr%f0/real(max(sr%m, 1), dp)
   end function own_measure

   !> A significant effect of plausible magnitude that the diagnosis resolves
   pure logical function finding(e)
      type(specimen_effect), intent(in) :: e
      finding = e%significant .and. e%plausible .and. .not. unresolved(e)
   end function finding

   !> Its magnitude below what the diagnosis resolves at 95 % (see below_resolved)
   pure logical function unresolved(e)
      type(specimen_effect), intent(in) :: e
      unresolved = .false.
      if (.not. (allocated(e%p_low) .and. allocated(e%p_lo) .and. allocated(e%p_hi))) return
      if (size(e%p_low) /= size(e%p_lo)) return
      unresolved = below_resolved(e%p_lo, e%p_hi, e%lo_open .or. e%hi_open, e%p_low)
   end function unresolved

   !> The per-specimen report (Markdown)
   function specimen_report(sr) result(lines)
      type(specimen_result), intent(in) :: sr
      character(len=report_line_len), allocatable :: lines(:)
      integer :: j, g
      character(len=:), allocatable :: ln, verdict
      allocate (lines(0))
      call add('# Per-specimen diagnosis: '//trim(sr%name))
      call add('')
      ln = 'Constants fitted to the replicates'
      if (allocated(sr%peers)) ln = 'Constants fitted to '//sr%peers
      if (allocated(sr%carried)) then
         if (len(sr%carried) > 0) ln = ln//' with '//sr%carried
      end if
      do j = 1, size(sr%replicates)
         ln = ln//trim(merge(': ', ', ', j == 1))//' '//trim(sr%replicates(j))
      end do
      call add(ln//' (objective '//real_str(sr%f_rep, 'es10.3')//'):')
      ln = ''
      do j = 1, size(sr%c)
         if (j > 1) ln = ln//', '
         ln = ln//trim(sr%cnames(j))//' = '//real_str(sr%c(j), 'es10.4')
      end do
      call add(ln//'.')
      if (allocated(sr%c_bound)) then
         if (any(sr%c_bound /= 0)) then
            call add('The replicates'' fit ran to a search bound of &fit for '// &
               bound_list(sr%cnames, side=sr%c_bound)//': the '// &
               'replicates do not bound it there, and what the specimen is set against rests on where '// &
               'the search stopped.')
         end if
      end if
      call add('')
      if (sr%f_joint >= 0.0_dp) then
         ln = trim(sr%name)//' predicted with them: objective '//real_str(sr%f0, 'es10.3')//' on '// &
              str(sr%m)//' points; its noise (sd of its '//trim(sr%unit)//' '//real_str(sr%noise_sd, 'es9.2')// &
              ') explains '//real_str(sum(sr%nv), 'es10.3')
         if (allocated(sr%w)) ln = ln//', and the constants'' own uncertainty (their covariance from the '// &
            'replicates'' noise, carried linearly to the specimen) '//real_str(sr%pred, 'es10.3')
         call add(ln//'.')
         call add('Fitted together with its replicates (no effect; the constants refitted to all the tests), '// &
            'its objective is '//real_str(sr%f_joint, 'es10.3')//'; structured gap '//real_str(sr%gap, 'es10.3')// &
            ' (what no constants take up, less the noise part) against a floor of '//real_str(sr%floor, 'es10.3')// &
            ' ('//real_str(gap_z, 'f0.0')//' standard errors of the gap noise alone leaves).')
      else
         call add(trim(sr%name)//' predicted with them: objective '//real_str(sr%f0, 'es10.3')//' on '// &
            str(sr%m)//' points, of which the noise (sd '//real_str(sr%noise_sd, 'es9.2')//' '// &
            trim(sr%unit)//') explains '//real_str(sr%noise, 'es10.3')//'; structured gap '// &
            real_str(sr%gap, 'es10.3')//'.')
         if (allocated(sr%w)) call add('The noise part includes '//real_str(sr%pred, 'es10.3')//' that the '// &
            'constants'' own uncertainty explains (their covariance from the given constants'' noise, carried '// &
            'linearly to the specimen).')
      end if
      if (sr%noise_corr > 0.0_dp) call add('Its noise sd from second differences '//str(corr_lag)// &
         ' samples apart is '//real_str(sr%noise_corr, 'f0.2')//' times that from neighbours (1 for independent '// &
         'noise; above '//real_str(correlated_ratio, 'f0.1')//' the noise is correlated from sample to sample, '// &
         'and the floor and BIC, which assume independent noise, overstate the evidence).')
      if (allocated(sr%rep_ms)) then
         if (size(sr%rep_ms) > 0) then
            ln = 'Its objective at these constants'//trim(merge(' per point', '          ', sr%per_point))// &
                 ', '//real_str(own_measure(sr), 'es9.2')//', against each replicate''s own there (fitted to them):'
            do j = 1, size(sr%rep_ms)
               ln = ln//trim(merge(' ', ',', j == 1))//' '//trim(sr%replicates(j))//' '//real_str(sr%rep_ms(j), 'es9.2')
            end do
            call add(ln//'.')
            if (typical(sr)) call add(trim(sr%name)//' is fitted by its replicates'' constants no worse than '// &
               'one of them fits itself: it does not stand out from them, and what the effects below take up '// &
               'is a gap the model leaves in these tests alike, not how this specimen differs from the others.')
         end if
      end if
      call add('')
      if (sr%f_joint >= 0.0_dp) then
         call add('Each effect fitted to '//trim(sr%name)//' alone, the constants refitted to it and its '// &
            'replicates together, each test weighted by its points over its mean square; its BIC change '// &
            'against that joint fit without the effect, so that what the replicates leave open of the '// &
            'constants is open to both. Ranked by BIC (significant: BIC falls by more than '// &
            real_str(bic_margin, 'f0.0')//'); magnitudes and objectives at the joint fit''s constants; '// &
            'intervals 95 % profile likelihood with those constants held, the leading effect''s with the '// &
            'constants refitted to all the tests at each point ("open": the data do not bound that end):')
      else
         if (allocated(sr%w)) then
            call add('Each effect fitted to '//trim(sr%name)//' alone, the constants fixed; ranked by BIC '// &
               '(significant: BIC falls by more than '//real_str(bic_margin, 'f0.0')//'), taken in the '// &
               'residual''s covariance with the constants'' uncertainty beside the noise, whose scale is fitted; '// &
               'intervals 95 % profile likelihood ("open": the data do not bound that end):')
         else
            call add('Each effect fitted to '//trim(sr%name)//' alone, the constants fixed; ranked by BIC '// &
               '(significant: BIC falls by more than '//real_str(bic_margin, 'f0.0')//'); intervals 95 % '// &
               'profile likelihood at those constants, without their uncertainty ("open": the data do not '// &
               'bound that end):')
         end if
      end if
      call add('')
      if (allocated(sr%w)) then
         call add('Power: of that rule against the effect at the low end of its realistic range, from the '// &
            'chi-square of its signal there (simulated) in the residual''s covariance with the constants'' '// &
            'uncertainty beside the noise, at the scale the residual is fitted to: the larger the misfit '// &
            'the constants leave, the less a small effect shows against it.')
      else
         call add('Power: of that rule against the effect at the low end of its realistic range, from the '// &
            'chi-square of its signal there (simulated) at the prediction''s residual: the larger the misfit '// &
            'the constants leave, the less a small effect shows against it.')
      end if
      call add('')
      call add('| rank | effect | magnitude [95 % interval] | objective | BIC change | gap removed | verdict | '// &
               'low end | chi-square there | power |')
      call add('|---|---|---|---|---|---|---|---|---|---|')
      do j = 1, size(sr%effects)
         associate (e => sr%effects(j))
            ln = magnitudes(e, '; ', sr%stress_unit)
            if (e%significant .and. e%plausible .and. unresolved(e)) then
               verdict = 'significant, below what is resolved'
            else if (e%significant .and. e%plausible) then
               verdict = 'significant'
            else if (e%significant) then
               verdict = 'significant, implausible magnitude'
            else if (e%plausible) then
               verdict = 'not significant'
            else
               verdict = 'not significant, implausible magnitude'
            end if
            call add('| '//str(j)//' | '//trim(e%name)//' | '//ln//' | '//real_str(e%f_after, 'es10.3')// &
               ' | '//real_str(e%dbic, 'f0.1')//' | '//real_str(100.0_dp*e%removed, 'f0.0')//' % | '// &
               verdict//' | '//trim(e%low_what)//' | '//power_cells(e%lambda_low, e%power_low)//' |')
         end associate
      end do
      call add('')
      call add('**Verdict:** '//specimen_verdict(sr))
      call add('')
      if (sr%nevals_rep > 0) then
         call add(str(sr%nevals_rep)//' simulations of the replicates (their fit), '// &
                  str(sr%nevals - sr%nevals_rep)//' of the specimen alone or with them (its effects, the joint '// &
                  'fits and the intervals).')
      else
         ! (constants given: no fit of the replicates to count apart)
         call add(str(sr%nevals)//' simulations, the constants given (the specimen''s effects and intervals, and '// &
                  'the replicates'' covariance where one is carried).')
      end if
   contains
      subroutine add(text)
         character(len=*), intent(in) :: text
         call add_line(lines, text)
      end subroutine add

   end function specimen_report

   !> The per-specimen verdict: the effect that explains how the specimen differs from its
   !> replicates (or, where it does not stand out from them, the gap it shares with them),
   !> in words scaled with the evidence, with its magnitudes
   function specimen_verdict(sr) result(verdict)
      type(specimen_result), intent(in) :: sr
      character(len=:), allocatable :: verdict
      character(len=:), allocatable :: ln, subject
      character(len=16), allocatable :: names(:)
      real(dp), allocatable :: power(:)
      type(hidden_effect), allocatable :: hidden(:)
      integer :: j, lead, best
      logical :: rest_low
      character(len=:), allocatable :: peers
      ! (what the specimen is set against: its replicates, or the fit tests of a diagnosis)
      peers = 'its replicates'
      if (allocated(sr%peers)) peers = sr%peers
      ! What an effect explains: how the specimen differs from its replicates, or where it
      ! does not stand out from them, the gap it shares with them
      if (typical(sr)) then
         subject = ' the gap of '//trim(sr%name)//' at '//peers//''' constants'
      else
         subject = ' how '//trim(sr%name)//' differs from '//peers
      end if
      verdict = 'no effect explains'//subject
      call specimen_lead(sr, lead, best)
      if (lead > 0) then
         associate (e => sr%effects(lead))
            ! As in the held-out diagnosis: "explains" for most of the structured gap, or
            ! where what it leaves lies below the floor (the noise part is an estimate: a
            ! temperature offset recovered to 0.1 K removed 51 % of a gap the noise estimate,
            ! 11 % low, had made)
            rest_low = max(e%f_after - sum(sr%nv), 0.0_dp) <= sr%floor
            verdict = trim(e%name)//trim(merge(' explains       ', ' partly explains', &
                      e%removed >= most .or. sr%gap <= 0.0_dp .or. rest_low))//subject//': '
            if (sr%gap > 0.0_dp .and. .not. e%removed > 0.0_dp) then
               ! Significant by BIC while it removes none of the structured gap (which its
               ! rest below the floor does not make an explanation of)
               verdict = trim(e%name)//' lowers BIC by '//real_str(-e%dbic, 'f0.1')//' for'// &
                         subject//' but removes none of its structured gap ('// &
                         real_str(100.0_dp*e%removed, 'f0.0')//' %)'// &
                         trim(merge(', which lies below its floor', '                            ', &
                                    sr%gap <= sr%floor))
            else if (sr%gap > 0.0_dp) then
               verdict = verdict//real_str(100.0_dp*e%removed, 'f0.0')//' % of its structured gap'// &
                         trim(merge(', the rest below its floor', '                          ', &
                                    rest_low .and. e%removed < most))//', BIC '//real_str(e%dbic, 'f0.1')
            else
               ! Significant by its form although the objective as a whole is at the noise level
               verdict = verdict//'BIC '//real_str(e%dbic, 'f0.1')//', a difference below the noise level of '// &
                         'the objective as a whole'
            end if
         end associate
         ! Effects within bic_margin of the best explain the difference as well
         ln = ''
         do j = best, size(sr%effects)
            if (j /= lead .and. finding(sr%effects(j)) .and. &
                sr%effects(j)%dbic < sr%effects(best)%dbic + bic_margin) ln = ln//', '//trim(sr%effects(j)%name)
         end do
         if (len(ln) > 0) verdict = verdict//'; as well (BIC within '//real_str(bic_margin, 'f0.0')//'): '//ln(3:)
         if (lead /= best) verdict = verdict//'; '//trim(sr%effects(lead)%name)//' leads as the simplest'
         associate (e => sr%effects(lead))
            if (allocated(e%p)) then
               if (size(e%p) > 0) verdict = verdict//'; fitted '//magnitudes(e, ', ', sr%stress_unit)
               verdict = verdict//hardening_note(e%name, e%p)
            end if
            if (allocated(e%p_bound) .and. allocated(e%pname) .and. allocated(e%p) .and. allocated(e%punit)) &
               verdict = verdict//params_bound_note(e%pname, e%p, e%p_bound, e%punit, sr%stress_unit)
         end associate
      end if
      if (sr%gap <= sr%floor .and. lead == 0) then
         if (sr%f_joint >= 0.0_dp) then
            verdict = 'one set of constants fits '//trim(sr%name)//' and '//peers//' to its noise level'
            if (sr%gap > 0.0_dp) verdict = verdict//' (its structured gap below its floor)'
         else
            verdict = trim(sr%name)//' is predicted to its noise level by '//peers
         end if
      end if
      if (lead == 0) then
         ! The best significant effect below what is resolved, said as what it is
         do j = 1, size(sr%effects)
            associate (e => sr%effects(j))
               if (e%significant .and. e%plausible .and. unresolved(e)) then
                  verdict = verdict//'; '//trim(e%name)//' lowers BIC by '//real_str(-e%dbic, 'f0.1')// &
                            ' but lies within '//real_str(resolved_share, 'f0.2')//' of the low end of its range ('// &
                            trim(e%low_what)//') at 95 %: below what the diagnosis resolves, not a finding'
                  exit
               end if
            end associate
         end do
         ! (copied: a component of an array of derived type is not contiguous)
         names = sr%effects%name
         power = sr%effects%power_low
         hidden = sr%effects%hidden
         verdict = verdict//missed_note(names, power, hidden, 'this test alone')
      end if
      if (typical(sr)) verdict = trim(sr%name)//' does not stand out from '//peers//' (objective'// &
         trim(merge(' per point', '          ', sr%per_point))//' at their constants '// &
         real_str(own_measure(sr), 'es9.2')//', theirs '// &
         real_str(minval(sr%rep_ms), 'es9.2')//' to '//real_str(maxval(sr%rep_ms), 'es9.2')//'); '//verdict
      ! (the residual at the replicates' constants; one that an effect takes up for the most
      ! part is the effect's, with sharp features that raise the ratio as correlated noise would)
      if (lead == 0) then
         verdict = verdict//correlated_note([sr%name], [sr%noise_corr], 'their constants leave')
      else if (sr%effects(lead)%removed < most) then
         verdict = verdict//correlated_note([sr%name], [sr%noise_corr], 'their constants leave')
      end if
   end function specimen_verdict

   !> e's fitted parameters with their 95 % intervals (interval_text), joined by sep
   function magnitudes(e, sep, stress_unit) result(text)
      type(specimen_effect), intent(in) :: e
      character(len=*), intent(in) :: sep
      character(len=*), intent(in) :: stress_unit   !< the model's stress unit
      character(len=:), allocatable :: text
      integer :: g
      text = ''
      do g = 1, size(e%p)
         if (g > 1) text = text//sep
         text = text//interval_text(e%pname(g), e%p(g), e%p_lo(g), e%p_hi(g), e%lo_open(g), e%hi_open(g), &
                                    bound_side(e, g), e%punit(g), stress_unit)
      end do
   end function magnitudes

   !> -1, 1: e's parameter g at the lower, upper end of its search box; 0: not
   pure integer function bound_side(e, g)
      type(specimen_effect), intent(in) :: e
      integer, intent(in) :: g
      bound_side = 0
      if (allocated(e%p_bound)) then
         if (g <= size(e%p_bound)) bound_side = e%p_bound(g)
      end if
   end function bound_side

   !> The report's table of effects as rows of specimen-<name>.csv, one per parameter of each
   !> effect in the report's order (rank: by BIC; leads: the verdict's effect; value, 95 %
   !> interval and unit as the report gives them, the stress in the model's unit; an open end
   !> or a parameter at its search bound as the report says; power -1: not computed)
   pure function specimen_csv(sr) result(rows)
      type(specimen_result), intent(in) :: sr
      character(len=:), allocatable :: rows(:)
      ! (long enough for two names of their greatest length, quoted, and the numbers)
      integer, parameter :: row_len = 4*name_len + 600
      character(len=row_len), allocatable :: r(:)
      character(len=:), allocatable :: side
      integer :: j, g, lead, best
      call specimen_lead(sr, lead, best)
      allocate (r(0))
      r = [character(len=row_len) :: r, specimen_csv_header]
      do j = 1, size(sr%effects)
         associate (e => sr%effects(j))
            do g = 1, size(e%p)
               side = ''
               if (allocated(e%p_bound)) then
                  if (g <= size(e%p_bound)) then
                     if (e%p_bound(g) /= 0) side = side_word(e%p_bound(g))
                  end if
               end if
               r = [character(len=row_len) :: r, csv_field(trim(sr%name))//','//str(j)//','// &
                  csv_field(trim(e%name))//','//str(e%q)//','//real_str(e%f_after, 'es14.7')//','// &
                  number(e%dbic, 'f0.2')//','//real_str(e%removed, 'f0.4')//','// &
                  trim(merge('yes', 'no ', e%significant))//','//trim(merge('yes', 'no ', e%plausible))//','// &
                  trim(merge('yes', 'no ', j == lead))//','//csv_field(trim(e%pname(g)))//','// &
                  real_str(e%p(g), 'es14.7')//','//real_str(e%p_lo(g), 'es14.7')//','// &
                  real_str(e%p_hi(g), 'es14.7')//','//trim(merge('yes', 'no ', e%lo_open(g)))//','// &
                  trim(merge('yes', 'no ', e%hi_open(g)))//','// &
                  csv_field(trim(adjustl(unit_text(e%punit(g), sr%stress_unit))))//','//side//','// &
                  real_str(e%lambda_low, 'es12.5')//','//real_str(e%power_low, 'f0.4')]
            end do
         end associate
      end do
      rows = r
   contains
      !> x in format fmt; empty where it is no number (a joint fit that failed leaves huge)
      pure function number(x, fmt) result(text)
         real(dp), intent(in) :: x
         character(len=*), intent(in) :: fmt
         character(len=:), allocatable :: text
         text = ''
         if (abs(x) < 0.1_dp*huge(1.0_dp)) text = real_str(x, fmt)
      end function number
   end function specimen_csv
end module usharp_diagnose_specimen
