!> `usharp diagnose`: where a fit's gap to the data lies, which catalogue effect explains it
!> and how far adding the effect closes it, also on tests held out of the fit.
!>
!> 1. The fit tests are fitted without any effect (Levenberg-Marquardt from the given
!>    constants, which are only a start, and from the &fit multi-start points when the deck
!>    asks for them; the held-out tests play no part); its residual is split into regions (usharp_regions) and set against the noise
!>    level estimated from each test's data (usharp_diagnose_baseline).
!> 2. Screening (score or Lagrange-multiplier test): at that fit, the Gauss-Newton decrease of
!>    the objective that an effect's parameters could give beyond what the constants can
!>    still give, from the forward-difference Jacobian; its BIC change is predicted
!>    (usharp_diagnose_screen).
!> 3. The leading candidates are refitted with the constants (the effect's magnitude gets a 95 %
!>    interval from s**2 (J'J)^-1), compared by AIC and BIC, and tried on the held-out tests:
!>    global parameters carry over, per-test parameters of a held-out test are fitted to it
!>    with the constants fixed (usharp_diagnose_refit). Significant: BIC falls by more than
!>    bic_margin; confirmed: also plausible in magnitude, the fit tests had a structured gap,
!>    and the structured gap of the held-out tests shrinks by at least confirm_shrink
!>    (held-out tests whose residual was already at the noise level must stay there).
!> 4. The verdict (usharp_diagnose_verdict): among confirmed effects without strong evidence
!>    between them the simplest leads; the refits that decide it run again from further
!>    starts. Last, when effects explain the gap equally well, the candidate test that would
!>    separate them (usharp_diagnose_separate). The report: usharp_diagnose_report.
module usharp_diagnose
   use, intrinsic :: iso_fortran_env, only: int64
   use usharp_kinds, only: dp
   use usharp_error, only: error_type, fatal_error, stat_input
   use usharp_model, only: constant_names
   use usharp_config, only: run_config
   use usharp_input_diagnose, only: check_holdout
   use usharp_objective, only: setup_problem
   use usharp_experiment, only: experiment_type, fits_strain, data_note
   use usharp_effects, only: effect_catalogue, param_per_test
   use usharp_strings, only: real_str, report_line_len
   use usharp_sort, only: order_of
   use usharp_diagnose_options, only: diagnose_options, diagnose_options_of, bic_margin, rival_share
   use usharp_diagnose_types, only: diagnose_context, diagnose_result, effect_outcome, held_quiet, &
                                    rest_at_noise, fit_structured, diagnose_progress, tell, step_done, &
                                    joint_wanted, named_effect, joint_decides, fit_gap_left, rest_wanted, &
                                    baseline_left_behind, physical_point, form_open, explains_resolved, most, &
                                    bound_list
   use usharp_diagnose_numerics, only: gn_decrease, held_rate
   use usharp_diagnose_baseline, only: fit_baseline, baseline_regions, baseline_step
   use usharp_diagnose_screen, only: screen
   use usharp_diagnose_refit, only: refit_candidates, refit_global, refit_deciding, refit
   use usharp_diagnose_verdict, only: conclude, joint_verdict, own_against_joint, carried_clause
   use usharp_diagnose_separate, only: separate
   use usharp_diagnose_specimen, only: specimen_result, specimen_run, specimen_report, specimen_verdict, &
                                       specimen_lead
   use usharp_diagnose_report, only: diagnose_report, write_report
   use usharp_diagnose_profile, only: profile_leading
   use usharp_diagnose_journal, only: diagnose_journal
   use usharp_diagnose_memo, only: run_memo
   implicit none
   private

   public :: diagnose_options, diagnose_result, effect_outcome, diagnose_run, diagnose_report
   public :: write_report, gn_decrease, diagnose_options_of, held_quiet, rest_at_noise, named_effect
   public :: fit_structured
   public :: joint_decides, simpler_rivals
   public :: diagnose_baseline, diagnose_context, diagnose_progress, n_leading, diagnose_journal
   public :: check_diagnosable

   !> Latin-hypercube starts of the constants for each refit that decides the verdict
   integer, parameter :: deciding_lhs = 2
   !> Most times the baseline is fitted again from a refit's better constants (see rebaseline)
   integer, parameter :: rebaseline_rounds = 2
   !> The steps made against an earlier baseline are named so in the report
   character(len=*), parameter :: earlier_tag = 'against an earlier baseline: '

   !> What every baseline of one diagnosis is fitted with (see diagnose_run): the data given
   !> directly (unallocated: read from the deck's files), who is told of each step, the
   !> journal and the runs made so far (null: none)
   type :: stage_sources
      type(experiment_type), allocatable :: experiments(:)
      procedure(diagnose_progress), pointer, nopass :: progress => null()
      type(diagnose_journal), pointer :: journal => null()
      type(run_memo), pointer :: memo => null()
   end type stage_sources

contains

   !> Diagnose the fit of cfg's tests from cfg's constants (a start: the baseline is fitted to
   !> the fit tests, and fitted again where a refit's constants fit them better: see
   !> rebaseline); experiments: the data given directly; progress: told of each step;
   !> journal: an open journal its units are kept in and replayed from (every rank runs the
   !> diagnosis with it; a stop signal ends it with an error naming --resume)
   subroutine diagnose_run(cfg, opts, res, error, experiments, progress, journal)
      type(run_config), intent(in) :: cfg
      type(diagnose_options), intent(in) :: opts
      type(diagnose_result), intent(out) :: res
      type(error_type), allocatable, intent(out) :: error
      type(experiment_type), intent(in), optional :: experiments(:)
      procedure(diagnose_progress), optional :: progress
      type(diagnose_journal), intent(inout), target, optional :: journal
      type(diagnose_context) :: ctx
      type(run_memo), target :: memo
      type(stage_sources) :: src
      call sources_of(src, experiments, progress, journal, memo)
      call diagnose_stage(cfg, opts, src, ctx, res, error)
      if (allocated(error)) return
      call held_own(cfg, opts, src, ctx, res, error)
      if (allocated(error)) return
      if (joint_wanted(res, opts%joint)) then
         call joint_stage(cfg, opts, src, ctx, res, error)
         if (allocated(error)) return
      end if
      if (allocated(res%own_note)) res%verdict = res%verdict//res%own_note//own_against_joint(res)
      call tell(ctx, 'done', res%nevals)
   end subroutine diagnose_run

   !> Where an effect explains the fit tests but does not carry to the held-out tests (see
   !> form_open), each held-out test diagnosed as a specimen beside the fit tests with that
   !> effect and its refit's constants carried (specimen_run): what the held-out tests have
   !> of their own beyond it. The prediction tests one effect at a time, so a held-out test
   !> that differs from the fit tests by a second effect leaves the first unconfirmed (a
   !> softening shared by every test, with the held-out relaxation test also 10 K colder,
   !> had come out as scatter: softening, 100 % of the fit tests' gap, made that test worse).
   !> Of several such effects the lowest BIC is carried; one with parameters per test is
   !> not (its held-out values are fitted to them already).
   subroutine held_own(cfg, opts, src, ctx, res, error)
      type(run_config), intent(in) :: cfg
      type(diagnose_options), intent(in) :: opts
      type(stage_sources), intent(in) :: src
      type(diagnose_context), intent(in) :: ctx
      type(diagnose_result), intent(inout) :: res
      type(error_type), allocatable, intent(out) :: error
      type(run_config) :: fcfg
      type(specimen_result) :: sr
      logical, allocatable :: free(:)
      character(len=:), allocatable :: carried
      type(error_type), allocatable :: err
      integer :: j, f, g, lead, best
      f = 0
      if (.not. allocated(res%held)) return
      if (.not. any(res%held) .or. held_quiet(res)) return
      ! (a leader that explains both sets leaves nothing for a second effect)
      if (res%leading > 0) then
         if (explains_resolved(res%effects(res%leading), res)) return
      end if
      do j = 1, size(res%effects)
         associate (e => res%effects(j))
            ! It explains most of a structured gap of the fit tests, and makes the held-out
            ! tests worse or leaves them as they were: what it carries of their gap is below
            ! its floor (a third of their gap carried is a prediction that partly holds, not
            ! a second effect's sign; 0.02 % of it, nothing)
            if (.not. form_open(e, res)) cycle
            if (e%shrink_fit < most .or. e%shrink_held*res%gap_held > res%floor_held) cycle
            ! ... and fits the fit tests better than a confirmed leader, which carries
            if (res%leading > 0) then
               if (res%effects(res%leading)%dbic <= e%dbic + bic_margin) cycle
            end if
            if (ctx%cat(e%k)%sharing == param_per_test) cycle
            if (.not. (allocated(e%c) .and. allocated(e%p_all) .and. allocated(e%p) .and. allocated(e%pname))) cycle
            if (f == 0) then
               f = j
            else if (e%dbic < res%effects(f)%dbic) then
               f = j
            end if
         end associate
      end do
      if (f == 0) return
      associate (e => res%effects(f))
         call tell(ctx, 'the held-out tests beside the fit tests with '//trim(e%name), res%nevals)
         carried = trim(e%name)
         do g = 1, size(e%p)
            if (g == 1) then
               carried = carried//' ('
            else
               carried = carried//', '
            end if
            carried = carried//trim(e%pname(g))//' = '//real_str(e%p(g), 'es10.3')
         end do
         if (size(e%p) > 0) carried = carried//')'
         fcfg = config_at(cfg, ctx%prob%idx, e%c)
         ! Its parameters that the refit fitted: all that act, but a rate it held
         free = e%p_acts
         if (e%held .and. held_rate(ctx%cat(e%k)) > 0) free(held_rate(ctx%cat(e%k))) = .false.
         res%own_base = f
         res%own_note = '; '//carried_clause(e)//'; with it and its constants carried, each held-out test '// &
                        'beside the fit tests:'
         if (allocated(e%c_bound) .and. allocated(res%cnames)) then
            if (any(e%c_bound /= 0)) res%own_note = res%own_note//' (its refit ran away: '// &
               bound_list(res%cnames, e%c, e%c_bound)//' at a search bound of &fit)'
         end if
         allocate (res%own_report(0), res%own_f(size(ctx%ihold)))
         res%own_q = 0
         do j = 1, size(ctx%ihold)
            call specimen_run(fcfg, ctx%ihold(j), opts, .false., sr, err, src%experiments, &
                              replicates=ctx%ifit, carried_k=e%k, carried_p=e%p_all, carried_free=free, &
                              carried_text=carried, peers='the fit tests')
            if (allocated(err)) then
               ! (the one-effect diagnosis stands without this step)
               res%own_note = res%own_note//trim(merge('  ', '; ', j == 1))//' '//trim(cfg%tests(ctx%ihold(j))%name)// &
                              ' could not be diagnosed so: '//err%message
               res%own_base = 0
               exit
            end if
            res%nevals = res%nevals + sr%nevals
            res%own_report = [character(len=report_line_len) :: res%own_report, specimen_report(sr)]
            res%own_note = res%own_note//trim(merge('  ', '; ', j == 1))//' '//specimen_verdict(sr)//also_removing(sr)
            call specimen_lead(sr, lead, best)
            res%own_f(j) = sr%f0
            if (lead > 0) then
               res%own_f(j) = sr%effects(lead)%f_after
               res%own_q = res%own_q + sr%effects(lead)%q
            end if
         end do
         call step_done(res, 'the held-out tests beside the fit tests with '//trim(e%name))
      end associate
   end subroutine held_own

   !> The other significant effects of plausible magnitude that remove most of a held-out
   !> test's structured gap beside the carried effect (see held_own), with their BIC against
   !> the leader, as a clause ('' when none): one test can be fitted by several, and BIC
   !> alone tells them apart
   function also_removing(sr) result(text)
      type(specimen_result), intent(in) :: sr
      character(len=:), allocatable :: text
      integer :: j, lead, best
      text = ''
      call specimen_lead(sr, lead, best)
      if (lead == 0) return
      do j = 1, size(sr%effects)
         if (j == lead) cycle
         associate (o => sr%effects(j))
            if (.not. (o%significant .and. o%plausible .and. o%removed >= most)) cycle
            if (len(text) > 0) text = text//', '
            text = text//trim(o%name)//' (BIC '//trim(merge('+', '-', o%dbic >= sr%effects(lead)%dbic))// &
                   real_str(abs(o%dbic - sr%effects(lead)%dbic), 'f0.1')//')'
         end associate
      end do
      if (len(text) > 0) text = ' (also removing 80 % or more of its gap: '//text//')'
   end function also_removing

   !> One stage of a diagnosis, of the fit tests or of every test fitted together: the
   !> baseline, the steps after it, and the baseline fitted again from a refit's constants
   !> while they leave it behind (see rebaseline). clock0: the clock the steps are timed
   !> from (absent: the stage's own start); carried: further starts of the refits (see
   !> diagnose_context)
   subroutine diagnose_stage(cfg, opts, src, ctx, res, error, clock0, carried)
      type(run_config), intent(in) :: cfg
      type(diagnose_options), intent(in) :: opts
      type(stage_sources), intent(in) :: src
      type(diagnose_context), intent(out) :: ctx
      type(diagnose_result), intent(out) :: res
      type(error_type), allocatable, intent(out) :: error
      integer(int64), intent(in), optional :: clock0
      type(physical_point), intent(in), optional :: carried(:)
      integer :: round
      logical :: lower
      call baseline_stage(cfg, opts, src, ctx, res, error)
      if (allocated(error)) return
      if (present(clock0)) ctx%clock0 = clock0
      if (present(carried)) ctx%carried = carried
      call diagnose_effects(ctx, res, error)
      if (allocated(error)) return
      do round = 1, rebaseline_rounds
         if (baseline_left_behind(res) == 0) exit
         call rebaseline(cfg, opts, src, ctx, res, error, lower)
         if (allocated(error)) return
         if (.not. lower) exit
      end do
   end subroutine diagnose_stage

   !> The steps after the baseline: screening, refits, the verdict, the leading effect's
   !> profile intervals and the test that would separate effects alike
   subroutine diagnose_effects(ctx, res, error)
      type(diagnose_context), intent(inout) :: ctx
      type(diagnose_result), intent(inout) :: res
      type(error_type), allocatable, intent(out) :: error
      logical, allocatable :: fresh(:)
      real(dp), allocatable :: lower(:)
      real(dp) :: f_before
      integer :: counted
      associate (opts => ctx%opts)
      call screen(ctx, res, error)
      if (allocated(error)) return
      call step_done(res, 'screening')
      call refit_candidates(ctx, res, 1, n_leading(res, opts%n_refit), error)
      if (allocated(error)) return
      call step_done(res, 'refits of the leading candidates')
      call conclude(res)
      ! Before the report says that nothing in the catalogue explains a structured gap, or
      ! names an effect that leaves part of it, the candidates the screening ranked lower are
      ! refitted too: the score test can miss an effect whose fit first has to leave the
      ! baseline's basin of the constants (a temperature offset of 24.5 K screened 7th of 9
      ! at a predicted dBIC of -42; refitted, -133, ahead of the scatter that had led at -118).
      ! So too when only the held-out tests show a gap (see rest_wanted).
      if (rest_wanted(res)) then
         call refit_candidates(ctx, res, n_leading(res, opts%n_refit) + 1, size(res%effects), error)
         if (allocated(error)) return
         call step_done(res, 'refits of the lower-ranked candidates')
         call conclude(res)
      end if
      call refit_simpler(ctx, res, error)
      if (allocated(error)) return
      ! When no significant refit brings the fit tests' structured gap down to the noise
      ! level, the refits may all sit in the baseline's basin of the constants (data made
      ! with an initial state other than the virgin one: refits end at 83-97 % of the gap,
      ! the injected effect from other constants at 100 %): the baseline and every refit run
      ! again from Latin-hypercube starts of the constants.
      if (opts%global_starts > 0 .and. fit_gap_left(res)) then
         call tell(ctx, 'global starts', res%nevals)
         call refit_global(ctx, res, error)
         if (allocated(error)) return
         call step_done(res, 'global starts')
         call refit_candidates(ctx, res, 1, 0, error)
         if (allocated(error)) return
         call step_done(res, 'cross starts after the global starts')
         call conclude(res)
      end if
      ! The refits that decide the verdict, from further starts
      if (any(res%effects%refitted .and. (res%effects%confirmed .or. res%effects%dbic < 0.0_dp))) then
         call tell(ctx, 'refits that decide the verdict, from further starts', res%nevals)
         call refit_deciding(ctx, res, deciding_lhs, error)
         if (allocated(error)) return
         call step_done(res, 'deciding refits from further starts')
         call conclude(res)
      end if
      ! The further starts can take a leader's confirmation away (a shift fell from 80.7 to
      ! 72.6 % of the held-out gap): the candidates the screening ranked lower are then
      ! refitted as they would have been before (a lag of 0.12 s, screened 4th, was never
      ! refitted and nothing was named)
      if (rest_wanted(res)) then
         fresh = .not. res%effects%refitted .and. res%effects%pred_drop > 0.0_dp
         if (any(fresh)) then
            call refit_candidates(ctx, res, 1, size(res%effects), error, only=fresh)
            if (allocated(error)) return
            call step_done(res, 'refits of the lower-ranked candidates')
            call conclude(res)
            call refit_deciding(ctx, res, deciding_lhs, error, only=fresh)
            if (allocated(error)) return
            call step_done(res, 'deciding refits from further starts')
            call conclude(res)
         end if
      end if
      ! Again for a leader that only the further starts made
      call refit_simpler(ctx, res, error)
      if (allocated(error)) return
      ! The leading effect's intervals where the curvature says little: profile likelihood
      call tell(ctx, 'profile', res%nevals)
      call profile_leading(ctx, res, error, lower)
      if (allocated(error)) return
      ! A profile whose walks met a point below the leader's refit shows that the refit was
      ! not the optimum: the leader refitted from there (its magnitudes, held-out prediction,
      ! BIC and shares then belong to the point its intervals are about), the verdict drawn
      ! again and the (new) leader profiled about its end point
      if (allocated(lower)) then
         counted = sum(res%effects%nevals)
         f_before = res%effects(res%leading)%f_after
         call refit(ctx, res, res%effects(res%leading), error, from=lower)
         if (allocated(error)) return
         res%nevals = res%nevals + sum(res%effects%nevals) - counted
         if (res%effects(res%leading)%f_after < f_before) res%effects(res%leading)%f_unprofiled = f_before
         call conclude(res)
         call profile_leading(ctx, res, error)
         if (allocated(error)) return
      end if
      call step_done(res, 'profile intervals')
      ! Last: when effects explain the gap equally well, the test that would separate them
      call separate(ctx, res)
      call step_done(res, 'separating test')
      end associate
   end subroutine diagnose_effects

   !> The simplest of the effects that explain the gap alike leads, but only refitted ones
   !> can be compared. A leader with parameters per test is checked against the simpler
   !> effects that could explain as much (see simpler_rivals)
   subroutine refit_simpler(ctx, res, error)
      type(diagnose_context), intent(inout) :: ctx
      type(diagnose_result), intent(inout) :: res
      type(error_type), allocatable, intent(out) :: error
      logical, allocatable :: simpler(:)
      if (res%leading == 0) return
      simpler = simpler_rivals(res, ctx%cat(res%effects(res%leading)%k)%sharing == param_per_test)
      if (.not. any(simpler)) return
      call refit_candidates(ctx, res, 1, size(res%effects), error, only=simpler)
      if (allocated(error)) return
      call step_done(res, 'refits of simpler candidates')
      call conclude(res)
   end subroutine refit_simpler

   !> The effects not yet refitted that a leader with parameters per test (per_test) is
   !> checked against: those with fewer parameters that the screening found significant, or
   !> whose predicted fall is at least rival_share of the leader's. Its parameters grow with
   !> the tests, and on a held-out test they are fitted to it, not predicted, so it can lead
   !> by its freedom alone (a scatter of 4 parameters had led for a temperature offset of
   !> -21.1 K that screened 4th, an effect of 2). The screening's BIC is not enough: at a
   !> baseline whose constants ran to their bounds a temperature offset of -22.4 K was
   !> predicted to fall by 0.88, more than the leading scatter's 0.55, but at a BIC of +14.9
   !> (the linear step made the test already fitted worse); refitted, it led at -1271.5
   pure function simpler_rivals(res, per_test) result(simpler)
      type(diagnose_result), intent(in) :: res
      logical, intent(in) :: per_test  !< the leader's parameters are per test
      logical :: simpler(size(res%effects))
      simpler = .false.
      if (res%leading == 0 .or. .not. per_test) return
      associate (lead => res%effects(res%leading))
         simpler = .not. res%effects%refitted .and. res%effects%q < lead%q .and. &
                   (res%effects%pred_dbic < -bic_margin .or. res%effects%pred_drop >= rival_share*lead%pred_drop)
      end associate
   end function simpler_rivals

   !> The baseline fitted again from the constants of the refit that, with its effect off,
   !> fits the fit tests better than it (see baseline_left_behind), and every step after
   !> the baseline again from there: each effect is judged against the optimum of the
   !> constants that the refits found, not against a basin they left. The first round's
   !> simulations and steps count in this one's. lower: the baseline ended lower (else
   !> nothing after it ran and ctx, res are as they were, but for its simulations).
   subroutine rebaseline(cfg, opts, src, ctx, res, error, lower)
      type(run_config), intent(in) :: cfg
      type(diagnose_options), intent(in) :: opts
      type(stage_sources), intent(in) :: src
      type(diagnose_context), intent(inout) :: ctx
      type(diagnose_result), intent(inout) :: res
      type(error_type), allocatable, intent(out) :: error
      logical, intent(out) :: lower
      type(run_config) :: rcfg
      type(diagnose_context) :: rctx
      type(diagnose_result) :: rres
      integer :: j, k
      k = baseline_left_behind(res)
      call tell(ctx, 'baseline again from the constants of the '//trim(res%effects(k)%name)// &
                ' refit', res%nevals)
      ! A start from a better basin than the multi-start's best: one local search
      rcfg = config_at(cfg, ctx%prob%idx, res%effects(k)%c)
      call baseline_stage(rcfg, opts, src, rctx, rres, error)
      if (allocated(error)) return
      ! From constants that fit better it ends lower: if not, nothing is gained by going on
      lower = rres%f0 < res%f0
      if (.not. lower) then
         res%nevals = res%nevals + rres%nevals
         call step_done(res, 'baseline again from the constants of the '//trim(res%effects(k)%name)// &
                        ' refit: not lower')
         return
      end if
      rctx%clock0 = ctx%clock0
      if (allocated(ctx%carried)) rctx%carried = ctx%carried
      allocate (rctx%earlier(size(ctx%cat)))
      if (allocated(ctx%earlier)) rctx%earlier = ctx%earlier
      do j = 1, size(res%effects)
         if (res%effects(j)%refitted) rctx%earlier(res%effects(j)%k)%x = res%effects(j)%x_fit
      end do
      call diagnose_effects(rctx, rres, error)
      if (allocated(error)) return
      rres%f0_left = res%f0
      rres%rebased_by = trim(res%effects(k)%name)
      rres%c0 = res%c0
      rres%nevals = res%nevals + rres%nevals
      do j = 1, size(res%steps)
         if (index(res%steps(j)%name, earlier_tag) /= 1) res%steps(j)%name = earlier_tag//res%steps(j)%name
      end do
      do j = 1, size(rres%steps)
         if (rres%steps(j)%name == baseline_step) rres%steps(j)%name = 'baseline from the constants of the '// &
            trim(res%effects(k)%name)//' refit'
      end do
      rres%steps = [res%steps, rres%steps]
      rres%mark_nevals = rres%nevals
      res = rres
      ctx = rctx
   end subroutine rebaseline

   !> The held-out tests fitted too (see joint_wanted): the whole diagnosis again with every
   !> test fitted, from the baseline's constants; its verdict becomes this one's, worded for
   !> the weaker evidence (an effect found so was fitted to the tests it explains, not
   !> predicted), and its simulations and steps count in this one's
   subroutine joint_stage(cfg, opts, src, ctx, res, error)
      type(run_config), intent(in) :: cfg
      type(diagnose_options), intent(in) :: opts
      type(stage_sources), intent(in) :: src
      type(diagnose_context), intent(in) :: ctx
      type(diagnose_result), intent(inout) :: res
      type(error_type), allocatable, intent(out) :: error
      type(run_config) :: jcfg
      type(diagnose_options) :: jopts
      type(diagnose_context) :: jctx
      type(diagnose_result) :: jres
      type(physical_point), allocatable :: carried(:)
      integer :: j
      call tell(ctx, 'the held-out tests fitted too', res%nevals)
      ! Each refit of the fit tests, with its values fitted to the held-out tests, is a
      ! point of its refit with every test fitted
      allocate (carried(size(ctx%cat)))
      do j = 1, size(res%effects)
         if (.not. res%effects(j)%refitted .or. .not. allocated(res%effects(j)%p_all)) cycle
         carried(res%effects(j)%k)%c = res%effects(j)%c
         carried(res%effects(j)%k)%p = res%effects(j)%p_all
      end do
      ! The baseline's multi-start has searched the constants already
      jcfg = config_at(cfg, ctx%prob%idx, res%c)
      jcfg%diagnose%holdout = .false.
      jopts = opts
      jopts%joint = .true.
      call diagnose_stage(jcfg, jopts, src, jctx, jres, error, ctx%clock0, carried)
      if (allocated(error)) return
      res%nevals = res%nevals + jres%nevals
      res%steps = [res%steps, jres%steps]
      do j = size(res%steps) - size(jres%steps) + 1, size(res%steps)
         res%steps(j)%name = 'all tests fitted: '//res%steps(j)%name
      end do
      res%mark_nevals = res%nevals
      res%mark_clock = jres%mark_clock
      res%mark_cpu = jres%mark_cpu
      call joint_verdict(res, jres)
      res%joint = jres
   end subroutine joint_stage

   !> cfg with its fitted constants idx at c and no multi-start: a baseline fitted from
   !> constants that a search has reached is one local search from them
   function config_at(cfg, idx, c) result(at)
      type(run_config), intent(in) :: cfg
      integer, intent(in) :: idx(:)
      real(dp), intent(in) :: c(:)   !< the constants' values, in the model's units
      type(run_config) :: at
      integer :: j
      at = cfg
      do j = 1, size(idx)
         call at%model%set_constant(idx(j), c(j))
      end do
      at%fit%multistart = 0
   end function config_at

   !> How many of the screened effects to refit: the leading n_refit and those the screening
   !> cannot tell from them (significant, and a predicted BIC within 10 % of the last one or
   !> within bic_margin, or a predicted fall at least rival_share of the largest so far): a
   !> temperature offset that screened 4th at -984 against scatter's -1007 was never
   !> refitted, and scatter, which carries it with two parameters more, led; a second back
   !> stress of 1.37 ksi screened 4th at 87 % of the leader's fall and was never tried
   pure integer function n_leading(res, n_refit) result(n)
      type(diagnose_result), intent(in) :: res
      integer, intent(in) :: n_refit
      logical :: near_bic, near_fall
      n = min(n_refit, size(res%effects))
      if (n < 1) return
      do while (n < size(res%effects))
         associate (last => res%effects(n)%pred_dbic, next => res%effects(n + 1))
            if (.not. next%pred_dbic < -bic_margin) exit
            near_bic = next%pred_dbic < last + max(bic_margin, 0.1_dp*abs(last))
            near_fall = next%pred_drop >= rival_share*maxval(res%effects(1:n)%pred_drop)
            if (.not. (near_bic .or. near_fall)) exit
         end associate
         n = n + 1
      end do
   end function n_leading

   !> The first step of a diagnosis: the baseline fitted to the fit tests alone (the held-out
   !> tests' data are not read before it is fitted: only their prediction follows), its
   !> regions and floors; ctx is what the later steps work on
   subroutine diagnose_baseline(cfg, opts, ctx, res, error, experiments, progress, journal, memo)
      type(run_config), intent(in) :: cfg
      type(diagnose_options), intent(in) :: opts
      type(diagnose_context), intent(out) :: ctx
      type(diagnose_result), intent(out) :: res
      type(error_type), allocatable, intent(out) :: error
      type(experiment_type), intent(in), optional :: experiments(:)
      procedure(diagnose_progress), optional :: progress
      !> See diagnose_run
      type(diagnose_journal), intent(inout), target, optional :: journal
      !> The runs made so far, which it adds to (absent: each run is made)
      type(run_memo), intent(inout), target, optional :: memo
      type(stage_sources) :: src
      call sources_of(src, experiments, progress, journal, memo)
      call baseline_stage(cfg, opts, src, ctx, res, error)
   end subroutine diagnose_baseline

   !> The sources of a diagnosis from the optional arguments of diagnose_run and
   !> diagnose_baseline (the pointers valid while those arguments are)
   subroutine sources_of(src, experiments, progress, journal, memo)
      type(stage_sources), intent(out) :: src
      type(experiment_type), intent(in), optional :: experiments(:)
      procedure(diagnose_progress), optional :: progress
      type(diagnose_journal), intent(inout), target, optional :: journal
      type(run_memo), intent(inout), target, optional :: memo
      if (present(experiments)) src%experiments = experiments
      if (present(progress)) src%progress => progress
      if (present(journal)) src%journal => journal
      if (present(memo)) src%memo => memo
   end subroutine sources_of

   !> diagnose_baseline with the sources of the whole diagnosis
   subroutine baseline_stage(cfg, opts, src, ctx, res, error)
      type(run_config), intent(in) :: cfg
      type(diagnose_options), intent(in) :: opts
      type(stage_sources), intent(in) :: src
      type(diagnose_context), intent(out) :: ctx
      type(diagnose_result), intent(out) :: res
      type(error_type), allocatable, intent(out) :: error
      integer(int64) :: clock0
      call system_clock(clock0)
      call step_done(res, '')
      ! An unallocated src%experiments is an absent argument: the data are read
      call prepare(cfg, opts, ctx, res, error, src%experiments)
      if (allocated(error)) return
      call step_done(res, 'setup: data and problem')
      ! after prepare, which makes ctx anew
      ctx%clock0 = clock0
      ctx%progress => src%progress
      ctx%journal => src%journal
      ctx%memo => src%memo
      call tell(ctx, 'baseline fit', res%nevals)
      call fit_baseline(ctx, res, error)
      if (allocated(error)) return
      call baseline_regions(ctx, res, error)
      if (allocated(error)) return
      call step_done(res, 'baseline regions')
   end subroutine baseline_stage

   !> What keeps a diagnosis of cfg from starting (an input error), checked too before its
   !> folder and journal are made: a test simulated otherwise than by an internal integrator
   !> (the effects live in their extended model), a held-out set empty or of every test
   subroutine check_diagnosable(cfg, opts, error)
      type(run_config), intent(in) :: cfg
      type(diagnose_options), intent(in) :: opts
      type(error_type), allocatable, intent(out) :: error
      integer :: i
      do i = 1, size(cfg%tests)
         if (cfg%tests(i)%ext%enabled .or. cfg%solver%integrator == 'umat') then
            call fatal_error(error, cfg%path//": test '"//cfg%tests(i)%name//"': diagnose "// &
               'simulates with an internal integrator (no external backend, integrator '// &
               '''cvode'' or ''rodas4'')', stat_input)
            return
         end if
      end do
      if (.not. opts%joint) call check_holdout(cfg%diagnose, cfg%path, error)
   end subroutine check_diagnosable

   !> The context of a diagnosis: the fit problem of every test, the fit and held-out sets,
   !> each test's name, response, noise level and peak; errors for what it cannot diagnose
   subroutine prepare(cfg, opts, ctx, res, error, experiments)
      type(run_config), intent(in) :: cfg
      type(diagnose_options), intent(in) :: opts
      type(diagnose_context), intent(out) :: ctx
      type(diagnose_result), intent(inout) :: res
      type(error_type), allocatable, intent(out) :: error
      type(experiment_type), intent(in), optional :: experiments(:)
      logical, allocatable :: strain_fit(:)
      integer :: nt, i, j
      call setup_problem(cfg, ctx%prob, error, experiments)
      if (allocated(error)) return
      nt = size(cfg%tests)
      call check_diagnosable(cfg, opts, error)
      if (allocated(error)) return
      res%held = cfg%diagnose%holdout
      ctx%ifit = pack([(i, i=1, nt)], .not. res%held)
      ctx%ihold = pack([(i, i=1, nt)], res%held)
      allocate (res%names(nt), res%unit(nt), res%noise(nt), res%peak(nt), strain_fit(nt), res%data_notes(nt))
      res%stress_unit = cfg%units
      do i = 1, nt
         res%names(i) = cfg%tests(i)%name
         res%data_notes(i) = data_note(ctx%prob%targets(i)%exp, cfg%tests(i)%dt_out, bare=.true.)
         res%unit(i) = merge('strain (-)     ', 'stress ('//cfg%units//')   ', fits_strain(cfg%tests(i)))
         ! (from the baseline's residual, see baseline_regions)
         res%noise(i) = 0.0_dp
         res%peak(i) = ctx%prob%targets(i)%y_ex_max
         strain_fit(i) = fits_strain(cfg%tests(i))
      end do
      ctx%opts = opts
      ! A typical stress of the fit tests scales the catalogue (the held-out data unread)
      ctx%peak = maxval(res%peak, .not. res%held .and. .not. strain_fit)
      if (.not. any(.not. res%held .and. .not. strain_fit)) ctx%peak = maxval(res%peak, .not. res%held)
      ctx%h = cfg%fit%fd_step
      ctx%eff_base%dlnE_dT = opts%dlnE_dT
      ctx%eff_base%gamma3 = opts%gamma3
      ctx%cat = effect_catalogue(ctx%peak)
      res%dt_sample = sampling_interval(ctx)
      res%cnames = constant_names(cfg%model, ctx%prob%idx)
      res%c0 = [(cfg%model%get_constant(ctx%prob%idx(j)), j=1, size(ctx%prob%idx))]
   end subroutine prepare

   !> Sampling interval (s) of the fit tests: the finest of their median intervals between
   !> data points (a delay the finest-sampled test resolves counts)
   function sampling_interval(ctx) result(dt)
      type(diagnose_context), intent(in) :: ctx
      real(dp) :: dt
      real(dp), allocatable :: d(:)
      integer :: i, n
      dt = huge(1.0_dp)
      do i = 1, size(ctx%ifit)
         associate (t => ctx%prob%targets(ctx%ifit(i))%t)
            n = size(t)
            if (n < 2) cycle
            d = t(2:n) - t(1:n - 1)
            d = d(order_of(d))
            dt = min(dt, d((size(d) + 1)/2))
         end associate
      end do
      if (dt == huge(1.0_dp)) dt = 0.0_dp
   end function sampling_interval
end module usharp_diagnose
