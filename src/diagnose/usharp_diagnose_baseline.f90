!> The baseline of a diagnosis: the model without any effect fitted to the fit tests, its
!> residual on every test (held-out ones: the prediction) split into regions, the noise
!> level of each test's data, and the floors below which a set's structured gap is noise
module usharp_diagnose_baseline
   use usharp_kinds, only: dp
   use usharp_lapack, only: mat_mul
   use usharp_math, only: pow10_dp
   use usharp_error, only: error_type, fatal_error, stat_failure
   use usharp_strings, only: str
   use usharp_objective, only: fit_problem
   use usharp_experiment, only: fits_strain
   use usharp_effect_problem, only: effect_problem, new_effect_problem
   use usharp_regions, only: region_stat, region_of, point_classes, class_names, gap_se, &
                             inelastic_points, serration_in_runs, serration_stat, serration_p
   use usharp_optimiser, only: optimum_type, reason_itermax, reason_max_evals
   use usharp_diagnose_options, only: gap_z
   use usharp_diagnose_types, only: diagnose_context, diagnose_result, tell, step_done
   use usharp_diagnose_units, only: lm_unit, starts_unit
   use usharp_diagnose_numerics, only: set_constants_at, global_points, at_bound, lm_ftol, lm_itermax, &
                                       jacobian, test_sizes, block_sums, tight_jacobian, sandwich_covariance, &
                                      noise_variance, residual_noise, noise_correlation
   implicit none
   private

   public :: fit_baseline, converge_baseline, baseline_regions, per_test, all_regions, baseline_step

   !> The name of the baseline's step from the given constants (see diagnose_result%steps)
   character(len=*), parameter :: baseline_step = 'baseline from the given constants'

   !> Most rounds of lm_itermax iterations the baseline's search runs (see converge_baseline)
   integer, parameter :: baseline_rounds = 10
   !> A round that lowers the objective by less than this share ends the baseline's search:
   !> it creeps, and the rounds after it would too
   real(dp), parameter :: creep_share = 1.0e-4_dp

contains

   !> Baseline: the fit tests without any effect, from the given constants (a start) and,
   !> when &fit asks for multi-start, from its Latin-hypercube points too (the lowest end
   !> point is kept, its search continued while it stopped at its iteration limit: see
   !> converge_baseline); ctx's constants become the baseline's
   subroutine fit_baseline(ctx, res, error)
      type(diagnose_context), intent(inout) :: ctx
      type(diagnose_result), intent(inout) :: res
      type(error_type), allocatable, intent(out) :: error
      type(effect_problem) :: base
      type(optimum_type) :: opt
      real(dp), allocatable :: lo(:), hi(:)
      integer :: i
      call new_effect_problem(ctx%prob, ctx%ifit, 0, ctx%eff_base, ctx%peak, base)
      call base%bounds(lo, hi)
      call lm_unit(ctx%journal, base, min(max(base%start(), lo), hi), lo, hi, ctx%h, lm_ftol, lm_itermax, &
                   ctx%opts%max_evals, opt, error, memo=ctx%memo)
      if (allocated(error)) return
      res%nevals = res%nevals + opt%nevals
      res%baseline_starts = 1 + max(ctx%prob%cfg%fit%multistart, 0)
      if (ctx%prob%cfg%fit%multistart > 0) then
         call step_done(res, baseline_step)
         call tell(ctx, 'baseline fit from '//str(res%baseline_starts)//' starts', res%nevals)
         call starts_unit(ctx%journal, base, global_points(ctx%prob%cfg, ctx%prob, ctx%prob%cfg%fit%multistart), &
                          lo, hi, ctx%h, ctx%opts%max_evals, opt, res%nevals, error, &
                          over_ranks=ctx%opts%over_ranks, memo=ctx%memo)
         if (allocated(error)) return
      end if
      call converge_baseline(ctx, base, lo, hi, opt, res, error)
      if (allocated(error)) return
      ! Global starts come later, only when the local refits leave a structured gap
      allocate (res%x_global(size(ctx%prob%idx), 0))
      res%c = pow10_dp(opt%x)
      call set_constants_at(ctx%prob, opt%x)
      res%f0 = opt%f
      res%m = base%nres()
      res%npts = test_sizes(ctx%prob, [(i, i=1, size(ctx%prob%targets))])
      res%c_bound = at_bound(opt%x, lo, hi)
      if (ctx%prob%cfg%fit%multistart > 0) then
         call step_done(res, 'baseline multi-start')
      else
         call step_done(res, baseline_step)
      end if
   end subroutine fit_baseline

   !> The baseline continued from its end point while its search ends at the iteration
   !> limit and a round still lowers the objective by more than creep_share (at most
   !> baseline_rounds rounds in all): every effect is judged against the baseline, so it must
   !> be the optimum of the constants. A thesis matrix stopped there at 2.453 after 100
   !> iterations while the constants alone reach 0.640; every near-null effect (a shift of
   !> 7 ms) then removed 93 % of the gap by the constants' refit, and led.
   !> res%baseline_converged: the last round ended otherwise than at the limit.
   subroutine converge_baseline(ctx, base, lo, hi, opt, res, error)
      type(diagnose_context), intent(inout) :: ctx
      type(effect_problem), intent(inout) :: base
      real(dp), intent(in) :: lo(:), hi(:)
      type(optimum_type), intent(inout) :: opt
      type(diagnose_result), intent(inout) :: res
      type(error_type), allocatable, intent(out) :: error
      type(optimum_type) :: more
      integer :: round
      do round = 2, baseline_rounds
         if (opt%reason /= reason_itermax) exit
         call lm_unit(ctx%journal, base, opt%x, lo, hi, ctx%h, lm_ftol, lm_itermax, &
                      ctx%opts%max_evals, more, error, memo=ctx%memo)
         if (allocated(error)) return
         res%nevals = res%nevals + more%nevals
         if (.not. more%f < opt%f) then
            ! a stationary point: a search from it finds nothing lower
            opt%reason = more%reason
            exit
         end if
         more%iterations = more%iterations + opt%iterations
         more%nevals = more%nevals + opt%nevals
         if (opt%f - more%f < creep_share*opt%f) then
            opt = more
            exit
         end if
         opt = more
      end do
      res%baseline_iterations = opt%iterations
      res%baseline_converged = opt%reason /= reason_itermax .and. opt%reason /= reason_max_evals
   end subroutine converge_baseline

   !> Baseline residuals of every test (held-out ones: the prediction), their regions, the
   !> noise parts, structured gaps and floors of both sets; ctx%nv is set
   subroutine baseline_regions(ctx, res, error)
      type(diagnose_context), intent(inout) :: ctx
      type(diagnose_result), intent(inout) :: res
      type(error_type), allocatable, intent(out) :: error
      type(effect_problem) :: base_all
      real(dp), allocatable :: r0(:), yb(:), eps(:), eps_in(:)
      real(dp) :: pvar
      integer, allocatable :: npts(:)
      integer :: i, m, nt
      logical :: ok
      nt = size(ctx%prob%targets)
      call new_effect_problem(ctx%prob, [(i, i=1, nt)], 0, ctx%eff_base, ctx%peak, base_all)
      m = base_all%nres()
      allocate (r0(m), yb(m), eps(m), eps_in(m))
      call base_all%residual_at(base_all%start(), r0, ok, yb, eps, eps_in)
      if (.not. ok) then
         call fatal_error(error, 'the baseline fit fails to simulate a held-out test', stat_failure)
         return
      end if
      call points_of(ctx%prob, res, eps, eps_in)
      res%y_base = yb
      ctx%noise = residual_noise(ctx%prob, [(i, i=1, nt)], yb)
      res%noise = ctx%noise
      res%noise_corr = noise_correlation(ctx%prob, [(i, i=1, nt)], yb)
      ctx%nv = noise_variance(ctx%prob, [(i, i=1, nt)], res%noise)
      associate (nv => ctx%nv)
         res%per_test0 = per_test(ctx%prob, r0)
         res%regions = all_regions(ctx%prob, res, r0, yb, nv)
         res%noise_fit = sum(nv, .not. res%held(res%test_of))
         res%noise_held = sum(nv, res%held(res%test_of))
         res%gap_fit = max(sum(r0**2, .not. res%held(res%test_of)) - res%noise_fit, 0.0_dp)
         res%gap_held = max(sum(r0**2, res%held(res%test_of)) - res%noise_held, 0.0_dp)
         npts = [(size(ctx%prob%targets(i)%exp%y), i=1, nt)]
         res%floor_fit = gap_z*gap_se(nv, res%test_of, npts, .not. res%held)
         res%floor_held = gap_z*gap_se(nv, res%test_of, npts, res%held)
         res%gap_held_noise = res%gap_held
         res%floor_held_noise = res%floor_held
         if (any(res%held)) then
            call prediction_spread(ctx, base_all, res, pvar)
            res%noise_held = res%noise_held + res%pred_held
            res%gap_held = max(sum(r0**2, res%held(res%test_of)) - res%noise_held, 0.0_dp)
            res%floor_held = gap_z*sqrt((res%floor_held/gap_z)**2 + pvar)
         end if
      end associate
   end subroutine baseline_regions

   !> What the fitted constants' own uncertainty adds to the held-out objective: with J the
   !> residuals' Jacobian in the constants (fit rows Jf, held-out rows Jh), the constants'
   !> covariance C = (Jf'Jf)^+ Jf' N Jf (Jf'Jf)^+ from the fit tests' noise variances N (the
   !> sandwich), the prediction error's covariance P = Jh C Jh': mean tr(P) (res%pred_held)
   !> and variance 2 tr(P^2) (pvar) of the sum of its squares. Without it the clean data of a
   !> held-out test the fit tests constrain weakly (a creep test predicted from cycling and
   !> relaxation) show a structured gap that no effect explains.
   subroutine prediction_spread(ctx, ep, res, pvar)
      type(diagnose_context), intent(in) :: ctx
      type(effect_problem), intent(inout) :: ep
      type(diagnose_result), intent(inout) :: res
      real(dp), intent(out) :: pvar
      real(dp), allocatable :: r(:), jac(:, :), jf(:, :), jh(:, :), cov(:, :), cm(:, :)
      logical, allocatable :: fit_row(:)
      logical :: ok
      integer :: j
      res%pred_held = 0.0_dp
      pvar = 0.0_dp
      call tight_jacobian(ep, ep%start(), ctx%h, r, jac, ok)
      res%nevals = res%nevals + size(jac, 2) + 1
      if (.not. ok) return
      fit_row = .not. res%held(res%test_of)
      allocate (jf(count(fit_row), size(jac, 2)), jh(count(.not. fit_row), size(jac, 2)))
      do j = 1, size(jac, 2)
         jf(:, j) = pack(jac(:, j), fit_row)
         jh(:, j) = pack(jac(:, j), .not. fit_row)
      end do
      cov = sandwich_covariance(jf, pack(ctx%nv, fit_row))
      cm = mat_mul(cov, mat_mul(transpose(jh), jh))
      do j = 1, size(cm, 1)
         res%pred_held = res%pred_held + cm(j, j)
      end do
      pvar = 2.0_dp*sum(cm*transpose(cm))
   end subroutine prediction_spread

   !> Every point of every test in one list: time, data, test, history class and cycle from
   !> the control's kinematics, elastic or inelastic from the baseline's inelastic rate
   subroutine points_of(prob, res, eps, eps_in)
      type(fit_problem), intent(in) :: prob
      type(diagnose_result), intent(inout) :: res
      real(dp), intent(in) :: eps(:), eps_in(:)  !< the baseline's strain and inelastic strain, -
      integer :: i, n, k0
      integer, allocatable :: cls(:), cyc(:)
      logical, allocatable :: el(:)
      allocate (res%t(0), res%y_ex(0), res%test_of(0), res%cls(0), res%cycle(0), res%elastic(0))
      k0 = 0
      do i = 1, size(prob%targets)
         associate (tg => prob%targets(i), test => prob%cfg%tests(i))
            n = size(tg%t)
            allocate (cls(n), cyc(n), el(n))
            call point_classes(test%hist, tg%t, cls, cyc)
            el = .not. inelastic_points(eps(k0 + 1:k0 + n), eps_in(k0 + 1:k0 + n))
            k0 = k0 + n
            res%t = [res%t, tg%t]
            res%y_ex = [res%y_ex, tg%y_ex]
            res%test_of = [res%test_of, spread(i, 1, n)]
            res%cls = [res%cls, cls]
            res%cycle = [res%cycle, cyc]
            res%elastic = [res%elastic, el]
            deallocate (cls, cyc, el)
         end associate
      end do
   end subroutine points_of

   !> Objective per test from the residuals of all tests
   function per_test(prob, r) result(pt)
      type(fit_problem), intent(in) :: prob
      real(dp), intent(in) :: r(:)
      real(dp) :: pt(size(prob%targets))
      integer :: i
      pt = block_sums(test_sizes(prob, [(i, i=1, size(prob%targets))]), r)
   end function per_test

   !> Regions of every test: the whole test, each history class, each cycle, elastic and
   !> inelastic points, and 'serrated flow' where the inelastic points' residual oscillates
   !> (serration_p, on their concatenation or on one of their runs)
   function all_regions(prob, res, r, ysim, nv) result(regs)
      type(fit_problem), intent(in) :: prob
      type(diagnose_result), intent(in) :: res
      real(dp), intent(in) :: r(:), ysim(:), nv(:)
      type(region_stat), allocatable :: regs(:)
      real(dp), allocatable :: e(:)
      integer :: i, k0, n, c
      character(len=:), allocatable :: tag
      type(serration_stat) :: ser
      allocate (regs(0))
      k0 = 0
      do i = 1, size(prob%targets)
         n = size(prob%targets(i)%t)
         e = prob%targets(i)%y_ex - ysim(k0 + 1:k0 + n)
         tag = trim(res%names(i))
         if (res%held(i)) tag = tag//' (held out)'
         associate (rr => r(k0 + 1:k0 + n), vv => nv(k0 + 1:k0 + n), cls => res%cls(k0 + 1:k0 + n), &
                    cyc => res%cycle(k0 + 1:k0 + n), el => res%elastic(k0 + 1:k0 + n))
            regs = [regs, region_of(tag, 'whole test', spread(.true., 1, n), rr, e, vv)]
            do c = 1, size(class_names)
               if (any(cls == c)) regs = [regs, region_of(tag, trim(class_names(c)), cls == c, rr, e, vv)]
            end do
            if (.not. fits_strain(prob%cfg%tests(i))) then
               ! periods well below a branch (two per cycle)
               ser = serration_in_runs(e, .not. el, count(.not. el)/(12*maxval(cyc)))
               if (ser%p < serration_p) then
                  ! Ahead of the inelastic region of the same points: the name says what it is
                  regs = [regs, region_of(tag, 'serrated flow', .not. el, rr, e, vv)]
                  regs(size(regs))%structured = .true.
               end if
               regs = [regs, region_of(tag, 'elastic', el, rr, e, vv)]
               regs = [regs, region_of(tag, 'inelastic', .not. el, rr, e, vv)]
            end if
            do c = 1, maxval(cyc)
               if (any(cyc == c)) regs = [regs, region_of(tag, 'cycle '//str(c), cyc == c, rr, e, vv)]
            end do
         end associate
         k0 = k0 + n
      end do
   end function all_regions
end module usharp_diagnose_baseline
