!> Screening of a diagnosis (score or Lagrange-multiplier test): at the baseline fit, the
!> Gauss-Newton decrease of the objective that an effect's parameters could give beyond
!> what the constants can still give, from the forward-difference Jacobian, with a short
!> nonlinear run from zero and from a tenth of the physical limit; its BIC change predicted
module usharp_diagnose_screen
   use usharp_kinds, only: dp
   use usharp_lapack, only: mat_mul
   use usharp_math, only: log_dp
   use usharp_error, only: error_type, fatal_error, stat_failure
   use usharp_effects, only: effect_info, param_global, param_per_test, effect_nparams
   use usharp_effect_problem, only: effect_problem, new_effect_problem
   use usharp_optimiser, only: optimum_type
   use usharp_sort, only: order_of
   use usharp_diagnose_types, only: diagnose_context, diagnose_result, effect_outcome, tell, hidden_size
   use usharp_diagnose_units, only: lm_unit
   use usharp_diagnose_journal, only: unit_stopped
   use usharp_diagnose_numerics, only: jacobian, gn_decrease, free_params, effect_fit, &
                                       softening_starts, backstress2_starts, soften_rate0, low_end_deltas, bic_power, &
                                       test_sizes, block_sums, deviance_change, screening_steps, power_lambda, held_rate
   use usharp_diagnose_separate, only: finding_test, fit_amplitude, fit_rel_noise
   implicit none
   private

   public :: screen, basin_points

contains

   !> Score screening of every considered effect at the baseline fit; effects sorted by the
   !> predicted change of BIC
   subroutine screen(ctx, res, error)
      type(diagnose_context), intent(in) :: ctx
      type(diagnose_result), intent(inout) :: res
      type(error_type), allocatable, intent(out) :: error
      type(effect_problem) :: base
      real(dp), allocatable :: r0(:), jc(:, :), keys(:), step0(:), lin0(:)
      real(dp) :: d0
      integer, allocatable :: npts(:)
      integer :: i
      logical :: ok, complete
      call new_effect_problem(ctx%prob, ctx%ifit, 0, ctx%eff_base, ctx%peak, base)
      ! The baseline may lie at the edge of the model's admissible region for a constant (every
      ! step of it fails): screen with that constant held rather than give up the diagnosis
      call jacobian(base, base%start(), ctx%h, r0, jc, ok, hold_failed=.true., complete=complete)
      if (.not. ok) then
         call fatal_error(error, 'screening: the model fails near the baseline fit', stat_failure)
         return
      end if
      res%nevals = res%nevals + base%nevals
      allocate (step0(size(jc, 2)))
      call gn_decrease(jc, r0, d0, step0)
      ! Each test's sum of squares after the constants' own Gauss-Newton step: the reference
      ! of an effect's linear prediction
      npts = test_sizes(ctx%prob, ctx%ifit)
      lin0 = block_sums(npts, r0 + mat_mul(jc, step0))
      allocate (res%effects(size(ctx%opts%effects)))
      do i = 1, size(ctx%opts%effects)
         call tell(ctx, 'screening '//trim(ctx%cat(ctx%opts%effects(i))%name), res%nevals)
         call screen_one(ctx, ctx%opts%effects(i), r0, jc, complete, d0, npts, lin0, res%effects(i), &
                         res%nevals, error)
         if (allocated(error)) return
      end do
      ! By predicted BIC change, best first (the keys copied: a component of an array of
      ! derived type is not contiguous)
      keys = res%effects%pred_dbic
      res%effects = res%effects(order_of(keys))
   end subroutine screen

   !> Screening of effect k: the linear score test and short nonlinear runs
   subroutine screen_one(ctx, k, r0, jc, jc_complete, d0, npts, lin0, e, nevals, error)
      type(diagnose_context), intent(in) :: ctx
      !> Catalogue effect
      integer, intent(in) :: k
      !> Baseline residuals of the fit tests, their Jacobian in the constants
      real(dp), intent(in) :: r0(:), jc(:, :)
      !> Every column of jc from its first difference step (none held or turned)
      logical, intent(in) :: jc_complete
      !> Gauss-Newton decrease the constants alone give
      real(dp), intent(in) :: d0
      !> Points of each fit test; each test's sum of squares after the constants' own step
      integer, intent(in) :: npts(:)
      real(dp), intent(in) :: lin0(:)
      type(effect_outcome), intent(inout) :: e
      integer, intent(inout) :: nevals
      type(error_type), allocatable, intent(out) :: error
      type(effect_problem) :: ep
      type(optimum_type) :: opt
      real(dp), allocatable :: je(:, :), rr(:), x(:), step(:), lo(:), hi(:), steps(:)
      real(dp), allocatable :: xs(:, :), xe(:, :), x_from(:, :), fe(:)
      integer, allocatable :: idx(:)
      real(dp) :: d1, s, dev_lin, dev_end
      real(dp), allocatable :: r_end(:), sum0(:)
      integer :: j, nc, q
      logical :: ok, complete
      s = sum(r0**2)
      nc = size(ctx%prob%idx)
      call new_effect_problem(ctx%prob, ctx%ifit, k, ctx%eff_base, ctx%peak, ep)
      if (k == 8) ep%p0(2) = ctx%opts%gamma3
      if (k == 7) ep%p0(2) = soften_rate0
      ep%pfree = free_params(ep, ctx%ifit, .true.)
      x = ep%start()
      ! With the effect at zero the constants' columns are the baseline's (the same numbers:
      ! the extended model at zero is the plain model); only the effect's are differenced
      steps = screening_steps(ep, ctx%cat(k), ctx%ifit, ctx%h)
      if (jc_complete) then
         call jacobian(ep, x, ctx%h, rr, je, ok, known_r=r0, known_jac=jc, complete=complete, steps=steps)
      else
         call jacobian(ep, x, ctx%h, rr, je, ok, complete=complete, steps=steps)
      end if
      nevals = nevals + ep%nevals
      e%k = k
      e%name = ctx%cat(k)%name
      q = count(ep%pfree)
      e%q = q
      if (.not. ok) return
      call low_end_power(ctx, ep, r0, jc, je(:, nc + 1:), npts, e, nevals)
      allocate (step(nc + q))
      call gn_decrease(reshape([jc, je(:, nc + 1:)], [size(r0), nc + q]), r0, d1, step)
      ! The linear prediction per test (each test's residuals of a variance of their own)
      sum0 = block_sums(npts, r0 + mat_mul(jc, step(:nc)) + mat_mul(je(:, nc + 1:), step(nc + 1:)))
      dev_lin = deviance_change(npts, lin0, max(sum0, 1.0e-3_dp*lin0))
      deallocate (step)
      ! The score test is linear: an effect whose first steps leave the valley of the
      ! constants shows only after a few nonlinear steps, so a short Levenberg-Marquardt
      ! run (3 Jacobians) from the baseline screens too; the refit continues from it
      call effect_fit(ctx, k, ep)
      call ep%bounds(lo, hi)
      ! The baseline constants have already bent towards the effect, so zero can be a
      ! local minimum of a global effect: its short runs also start from a tenth of the
      ! physical limit with every sign, and the lowest end point is kept
      xs = screening_starts(ep, ctx%cat(k), ctx%peak)
      allocate (xe(size(xs, 1), 0), x_from(size(xs, 1), 0), fe(0))
      do j = 1, size(xs, 2)
         ! From a start away from zero the constants first have to come back: 5 steps
         ! (measured: holding the effect at the start while the constants alone move
         ! first, 6 + 3 steps, gave the same self-check table at twice the cost)
         ! The zero start is where the screening's Jacobian was taken: its first step uses it
         if (j == 1 .and. complete .and. size(xs, 1) == size(x) .and. size(je, 2) == size(x)) then
            if (all(min(max(xs(:, 1), lo), hi) == x)) then
               call lm_unit(ctx%journal, ep, x, lo, hi, ctx%h, 1.0e-9_dp, 3, ctx%opts%max_evals, opt, &
                            error, jac0=je, memo=ctx%memo)
            else
               call lm_unit(ctx%journal, ep, min(max(xs(:, j), lo), hi), lo, hi, ctx%h, 1.0e-9_dp, &
                            merge(3, 5, j == 1), ctx%opts%max_evals, opt, error, memo=ctx%memo)
            end if
         else
            call lm_unit(ctx%journal, ep, min(max(xs(:, j), lo), hi), lo, hi, ctx%h, 1.0e-9_dp, &
                         merge(3, 5, j == 1), ctx%opts%max_evals, opt, error, memo=ctx%memo)
         end if
         if (allocated(error)) then
            ! A start where the model fails is passed over; the zero start must work (and a
            ! stop signal ends the diagnosis)
            if (j == 1 .or. unit_stopped(ctx%journal)) return
            deallocate (error)
            cycle
         end if
         nevals = nevals + opt%nevals
         xe = reshape([xe, opt%x], [size(xs, 1), size(fe) + 1])
         x_from = reshape([x_from, min(max(xs(:, j), lo), hi)], [size(xs, 1), size(fe) + 1])
         fe = [fe, opt%f]
      end do
      ! The lowest end point leads; the others, best first, are kept for refits from
      ! several (refit_starts > 1; measured with 2: the same self-check table at 1.5 times
      ! the cost, so 1 by default)
      idx = order_of(fe)
      e%x = xe(:, idx(1))
      ! The rates the end points started from (see rate_rungs)
      j = held_rate(ctx%cat(k))
      if (j > 0 .and. count(ep%pfree) == size(ep%p0)) then
         e%rate_start = x_from(nc + j, idx(1))*ep%pscale(j)
         e%rate_alt = x_from(nc + j, idx(2:))*ep%pscale(j)
      end if
      xe = basin_points(xe, x_from, fe, s)
      e%x_alt = xe(:, idx(2:))
      e%q = count(ep%pfree)
      q = e%q
      e%pred_drop = max(d1 - d0, s - fe(idx(1)), 0.0_dp)
      ! The predicted BIC change from the better of the linear prediction and the short runs'
      ! lowest end point, each test's residuals of a variance of their own (as the refit's)
      sum0 = block_sums(npts, r0)
      allocate (r_end(size(r0)))
      call ep%residual_at(e%x, r_end, ok)
      nevals = nevals + 1
      dev_end = 0.0_dp
      if (ok) dev_end = deviance_change(npts, sum0, max(block_sums(npts, r_end), 1.0e-3_dp*sum0))
      e%pred_dbic = min(dev_lin, dev_end, 0.0_dp) + q*log_dp(real(size(r0), dp))
   end subroutine screen_one

   !> The power of the BIC rule against effect ep%k at the low end of its realistic range on
   !> the fit tests (see low_end_deltas, bic_power): the effect's signal there from the
   !> screening's Jacobian (jp: its columns, linear in the parameters), less what the
   !> constants take up (its projection on jc), each test's rows over the residual variance
   !> that BIC sees there (that test's baseline mean square); the refit's parameters are the
   !> degrees of freedom
   subroutine low_end_power(ctx, ep, r0, jc, jp, npts, e, nevals)
      type(diagnose_context), intent(in) :: ctx
      type(effect_problem), intent(in) :: ep
      real(dp), intent(in) :: r0(:), jc(:, :), jp(:, :)
      !> Points of each fit test (consecutive blocks of r0)
      integer, intent(in) :: npts(:)
      type(effect_outcome), intent(inout) :: e
      !> simulations made (the candidate tests' added)
      integer, intent(inout) :: nevals
      real(dp), allocatable :: d(:, :), d1(:, :), sig(:), w(:), var(:)
      real(dp) :: proj, lam
      integer :: g, i, gmin
      ! Each test's residual variance, its baseline mean square
      var = block_sums(npts, r0)/max(npts, 1)
      d = low_end_deltas(ep, ctx%cat(ep%k), ctx%ifit)
      ! A per-test effect is often one specimen's (a drift, a temperature offset): at its low
      ! end in one fit test alone the others carry no signal and the constants take up more
      ! of it, so the power stated is the least over every fit test together and each alone
      ! (a drift of -8.3e-8 1/s in the LCF test only was missed where the power with it in
      ! both fit tests was 1.00)
      if (ctx%cat(ep%k)%sharing == param_per_test .and. size(ctx%ifit) > 1) then
         do i = 1, size(ctx%ifit)
            d1 = low_end_deltas(ep, ctx%cat(ep%k), [ctx%ifit(i)])
            d = reshape([d, d1], [size(d, 1), size(d, 2) + size(d1, 2)])
         end do
      end if
      if (any(var <= 0.0_dp) .or. size(d, 2) == 0) return
      w = [(spread(1.0_dp/sqrt(var(i)), 1, npts(i)), i=1, size(npts))]
      e%lambda_low = huge(1.0_dp)
      gmin = 1
      do g = 1, size(d, 2)
         sig = w*mat_mul(jp, pack(d(:, g)/ep%pscale, ep%pfree))
         call gn_decrease(jc*spread(w, 2, size(jc, 2)), sig, proj)
         lam = max(sum(sig**2) - proj, 0.0_dp)
         ! the weakest low end: the (last) column of the least chi-square
         if (lam <= e%lambda_low) gmin = g
         e%lambda_low = min(e%lambda_low, lam)
      end do
      e%power_low = bic_power(e%lambda_low, count(free_params(ep, ctx%ifit, .false.)), size(r0))
      if (e%power_low < 0.95_dp) call hidden_bound()
   contains
      !> How much of the effect the fit tests could hide: the multiple of its low end (the
      !> weakest of them, d) at which the rule's power is 0.95 (its signal linear in the
      !> magnitude, as above), that magnitude where it is one number (a global parameter),
      !> and the candidate test that would find it (a per-test parameter at the fit tests'
      !> mean)
      subroutine hidden_bound()
         real(dp), allocatable :: dg(:), p(:), p1(:)
         character(len=64) :: unused
         integer :: q, nt, j, gp, i
         integer, allocatable :: idx(:)
         logical, allocatable :: nz(:)
         q = count(free_params(ep, ctx%ifit, .false.))
         if (.not. e%lambda_low > 0.0_dp) return
         dg = d(:, gmin)
         e%hidden%times = min(sqrt(power_lambda(0.95_dp, q, size(r0))/e%lambda_low), 1.0e4_dp)
         p = ep%p0 + e%hidden%times*dg
         nt = size(ctx%prob%targets)
         associate (info => ctx%cat(ep%k))
            if (info%sharing == param_per_test) then
               allocate (p1(info%nparam))
               do gp = 1, info%nparam
                  ! the mean over the fit tests that carry it at the low end (all, or one)
                  idx = [((gp - 1)*nt + ctx%ifit(i), i=1, size(ctx%ifit))]
                  nz = dg(idx) /= 0.0_dp
                  if (.not. any(nz)) nz = .true.
                  p1(gp) = sum(p(idx), mask=nz)/count(nz)
               end do
               ! (the mean's size: its magnitude per test is not one number)
               call hidden_size(info, p1, 1, ctx%peak, ctx%prob%cfg%units, unused, e%hidden%beyond)
            else
               p1 = p(:effect_nparams(info, 1))
               j = maxloc(abs(dg), 1)
               call hidden_size(info, p1, j, ctx%peak, ctx%prob%cfg%units, e%hidden%magnitude, &
                                e%hidden%beyond)
            end if
         end associate
         call finding_test(ep%prob%cfg%model, ep%k, p1, ctx%eff_base, ctx%prob%cfg%solver, fit_amplitude(ctx), &
                           fit_rel_noise(ctx), q, e%hidden%test, e%hidden%power, nevals)
      end subroutine hidden_bound
   end subroutine low_end_power

   !> The points of the short runs' basins that a refit tries from other constants
   !> (other_sign): each run's end point, or its start where the run found nothing below the
   !> baseline. Such a run has lost its start's effect (a softening started at +0.05 ended at
   !> a = 0.005, b = 0.001, no effect at all, and the refits from that point with the
   !> constants of Latin-hypercube starts stayed at the baseline, while the softening's
   !> basin lay at a = 0.17, b = 200)
   pure function basin_points(x_end, x_start, f_end, f_base) result(xb)
      !> end points and start points of the runs (one column each)
      real(dp), intent(in) :: x_end(:, :), x_start(:, :)
      !> objective at each end point, and the baseline's
      real(dp), intent(in) :: f_end(:), f_base
      real(dp) :: xb(size(x_end, 1), size(x_end, 2))
      integer :: j
      do j = 1, size(f_end)
         if (f_end(j) < (1.0_dp - 1.0e-6_dp)*f_base) then
            xb(:, j) = x_end(:, j)
         else
            xb(:, j) = x_start(:, j)
         end if
      end do
   end function basin_points

   !> Starts of the screening runs of a global effect with a physical limit: zero, then every
   !> sign combination of a tenth of the limit (non-negative parameters only positive); other
   !> effects start from zero only. Columns: x of ep.
   pure function screening_starts(ep, info, peak) result(xs)
      type(effect_problem), intent(in) :: ep
      type(effect_info), intent(in) :: info
      !> peak stress of the tests (stress unit)
      real(dp), intent(in) :: peak
      real(dp), allocatable :: xs(:, :)
      real(dp), allocatable :: x0(:), ps(:, :)
      integer :: nc, np, j, s, nsign, combo
      x0 = ep%start()
      nc = size(x0) - count(ep%pfree)
      np = count(ep%pfree)
      if ((ep%k == 7 .or. ep%k == 8) .and. np == 2) then
         ! The saturating softening of either sign, the second back stress of two
         ! saturations, each at a ladder of rates (softening_starts, backstress2_starts)
         if (ep%k == 7) ps = softening_starts(info)
         if (ep%k == 8) ps = backstress2_starts(peak, ep%p0(2))
         allocate (xs(size(x0), size(ps, 2)))
         xs = spread(x0, 2, size(ps, 2))
         xs(nc + 1, :) = ps(1, :)/ep%pscale(1)
         xs(nc + 2, :) = ps(2, :)/ep%pscale(2)
         return
      end if
      ! (nested: Fortran's .or. may evaluate plausible(1:np) even when np > 2)
      if (info%sharing /= param_global .or. np /= size(ep%p0) .or. np > 2) then
         xs = reshape(x0, [size(x0), 1])
         return
      end if
      if (any(info%plausible(1:np) >= huge(1.0_dp))) then
         xs = reshape(x0, [size(x0), 1])
         return
      end if
      nsign = 2**count(.not. info%nonneg(1:np))
      allocate (xs(size(x0), nsign + 1))
      xs(:, 1) = x0
      do combo = 0, nsign - 1
         xs(:, combo + 2) = x0
         s = combo
         do j = 1, np
            xs(nc + j, combo + 2) = 0.1_dp*info%plausible(j)/ep%pscale(j)
            if (.not. info%nonneg(j)) then
               if (mod(s, 2) == 1) xs(nc + j, combo + 2) = -xs(nc + j, combo + 2)
               s = s/2
            end if
         end do
      end do
   end function screening_starts
end module usharp_diagnose_screen
