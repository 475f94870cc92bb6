!> Numerical pieces the steps of a diagnosis share: forward-difference Jacobians of an
!> effect problem, the Gauss-Newton decrease, a scaled pseudo-inverse, Levenberg-Marquardt
!> from several starts, Latin-hypercube starts of the constants, and which of an effect's
!> parameters are free
module usharp_diagnose_numerics
   use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
   use usharp_kinds, only: dp
   use usharp_math, only: exp_dp, log_dp, log10_dp, pow10_dp
   use usharp_model, only: model_type
   use usharp_error, only: error_type
   use usharp_config, only: run_config
   use usharp_objective, only: fit_problem, test_residuals
   use usharp_effects, only: effect_info, effect_catalogue, n_effects, param_per_test, param_global
   use usharp_effect_problem, only: effect_problem, new_effect_problem
   use usharp_levenberg, only: levenberg_marquardt
   use usharp_optimiser, only: optimum_type
   use usharp_lapack, only: svd, mat_mul
   use usharp_sampling, only: latin_hypercube
   use usharp_rng, only: rng_type
   use usharp_diagnose_types, only: diagnose_context, deviance_change
   use usharp_diagnose_options, only: bic_margin, corr_lag
   use usharp_distributions, only: ncx2_sf
   use usharp_forcing, only: noise_sd, noise_lag_ratio
   use usharp_mpi, only: n_ranks, this_rank, share, sum_over_ranks, task_deal, ranks_that_ran
   use omp_lib, only: omp_get_max_threads
   implicit none
   private

   public :: set_constants_at, copy_constants, jacobian, gn_decrease, pseudo_inverse, best_of_starts
   public :: take_starts, global_points, lm_ftol, lm_itermax, lm_updates
   public :: judge_held_values
   public :: free_params, effect_fit, at_bound, at_box_end, softening_starts, soften_rate0, softening_reached, &
             backstress2_starts, rate_effect_start
   public :: limit_measures, below_resolved, resolved_share
   public :: low_end_deltas, low_end_starts, distinct_starts
   public :: screening_steps, bic_power, power_lambda, test_sizes, block_sums, deviance_change
   public :: tight_jacobian, sandwich_covariance, noise_variance, residual_noise, held_rate, ratio_beyond_doubt, &
             noise_correlation, &
             beyond_limit

   !> 1/strain, rate of the saturating softening where its screening holds it (it has no
   !> gradient at zero softening) and where its fits start: saturated over the first 1 % of
   !> accumulated inelastic strain
   real(dp), parameter :: soften_rate0 = 100.0_dp
   !> The rates of the second back stress's starts, as multiples of the screening's gamma3
   !> (see backstress2_starts): a fit stays in the basin of the rate it starts from, and the
   !> basins lie a factor of 2-5 apart in the rate
   real(dp), parameter :: b2_rates(4) = [0.5_dp, 2.0_dp, 10.0_dp, 50.0_dp]


   !> Levenberg-Marquardt's settings for a refit's runs: ftol, most iterations, and most
   !> accepted steps one difference Jacobian serves (Broyden-updated after each). The refits
   !> of real data creep along curved valleys for their 100 iterations; with the updates most
   !> iterations there cost one simulation, not one per parameter: the Alloy 617 diagnosis
   !> took 82813 simulations in place of 115790 (bench/diagnose.sh)
   real(dp), parameter :: lm_ftol = 1.0e-9_dp
   !> The share of an effect's low end below which the diagnosis does not resolve it (see
   !> below_resolved)
   real(dp), parameter :: resolved_share = 0.25_dp
   integer, parameter :: lm_itermax = 100, lm_updates = 4
   !> How near a bound (log10 units for the constants) a fitted value is at it (see at_bound)
   real(dp), parameter :: bound_tol = 1.0e-6_dp

   !> Integrator tolerances (rtol, atol on strain) of the Jacobians behind the constants'
   !> covariance and what it adds to a prediction (tight_jacobian): at the working tolerance
   !> two constants that trade off (log B and n) left the smallest eigenvalue of J'J to the
   !> integrator's error
   real(dp), parameter :: tight_tol(2) = [1.0e-9_dp, 1.0e-12_dp]

contains

   !> The fitted constants of prob's model set to x (log10 of them); the model is to be set
   !> up before it is simulated
   pure subroutine set_constants_at(prob, x)
      type(fit_problem), intent(inout) :: prob
      real(dp), intent(in) :: x(:)
      integer :: j
      do j = 1, size(prob%idx)
         call prob%cfg%model%set_constant(prob%idx(j), pow10_dp(x(j)))
      end do
   end subroutine set_constants_at

   !> Every constant of prob's model from model (of the same kind); to be set up before use
   pure subroutine copy_constants(model, prob)
      class(model_type), intent(in) :: model
      type(fit_problem), intent(inout) :: prob
      integer :: j
      do j = 1, model%n_constants()
         call prob%cfg%model%set_constant(j, model%get_constant(j))
      end do
   end subroutine copy_constants

   !> Forward-difference Jacobian of ep's residuals at x (step h, backwards at an upper bound)
   !> and the residuals r0 there, as one parallel batch; ok false if a point failed. With
   !> hold_failed, a column whose every step fails is left at zero (that parameter held).
   !> With known_r and known_jac (the residuals at x and the first columns, from a problem
   !> that gives the same numbers there: the baseline for an effect at zero), x is simulated
   !> once to check that it does, and only the other columns are differenced. complete: every
   !> column from its first step (none failed or went another way).
   subroutine jacobian(ep, x, h, r0, jac, ok, hold_failed, known_r, known_jac, complete, steps)
      type(effect_problem), intent(inout) :: ep
      real(dp), intent(in) :: x(:), h
      real(dp), allocatable, intent(out) :: r0(:), jac(:, :)
      logical, intent(out) :: ok
      logical, intent(in), optional :: hold_failed
      real(dp), intent(in), optional :: known_r(:), known_jac(:, :)
      logical, intent(out), optional :: complete
      !> Difference step of each column (units of x) where larger than h
      real(dp), intent(in), optional :: steps(:)
      real(dp), allocatable :: xs(:, :), rs(:, :), fs(:), lo(:), hi(:), step(:), r1(:, :)
      real(dp) :: f1(1)
      logical, allocatable :: oks(:)
      logical :: ok1(1)
      type(error_type), allocatable :: error
      integer :: n, j, attempt, nk, nb
      n = size(x)
      call ep%bounds(lo, hi)
      nk = 0
      if (present(known_r) .and. present(known_jac)) then
         allocate (r1(ep%nres(), 1))
         call ep%residuals(reshape(x, [n, 1]), r1, f1, ok1, error)
         if (ok1(1) .and. .not. allocated(error) .and. size(known_jac, 2) <= n) then
            if (all(r1(:, 1) == known_r)) nk = size(known_jac, 2)
         end if
         if (allocated(error)) deallocate (error)
      end if
      ! Column 1: x itself, unless it is known; then the columns nk+1..n
      nb = merge(0, 1, nk > 0)
      allocate (xs(n, nb + n - nk), rs(ep%nres(), nb + n - nk), fs(nb + n - nk), oks(nb + n - nk), step(n))
      do j = 1, size(xs, 2)
         xs(:, j) = x
      end do
      step = h
      if (present(steps)) step = max(h, steps)
      do j = nk + 1, n
         step(j) = merge(-step(j), step(j), x(j) + step(j) > hi(j))
         xs(j, nb + j - nk) = x(j) + step(j)
      end do
      call ep%residuals(xs, rs, fs, oks, error)
      if (nk > 0) then
         ok = .not. allocated(error)
      else
         ok = oks(1) .and. .not. allocated(error)
      end if
      if (present(complete)) complete = all(oks)
      ! A step that failed (the model's admissible region ends there) goes the other way,
      ! then shorter, down to h/100
      attempt = 0
      do while (ok .and. .not. all(oks) .and. attempt < 5)
         attempt = attempt + 1
         do j = nk + 1, n
            if (oks(nb + j - nk)) cycle
            step(j) = -step(j)
            if (mod(attempt, 2) == 0) step(j) = 0.1_dp*step(j)
            xs(j, nb + j - nk) = x(j) + step(j)
         end do
         call ep%residuals(xs, rs, fs, oks, error)
         if (nk > 0) then
            ok = .not. allocated(error)
         else
            ok = oks(1) .and. .not. allocated(error)
         end if
      end do
      if (nk > 0) then
         r0 = known_r
      else
         r0 = rs(:, 1)
      end if
      allocate (jac(size(r0), n))
      jac = 0.0_dp
      if (nk > 0) jac(:, 1:nk) = known_jac
      do j = nk + 1, n
         if (oks(nb + j - nk)) jac(:, j) = (rs(:, nb + j - nk) - r0)/step(j)
      end do
      if (present(hold_failed)) then
         if (hold_failed) return
      end if
      ok = ok .and. all(oks(nb + 1:))
   end subroutine jacobian

   !> Gauss-Newton decrease g'(J'J)^+ g (g = J'r) of sum(r**2) in the span of the columns of
   !> jac, and the step -(J'J)^+ g; columns scaled to unit norm, directions below 1e-10 of the
   !> largest singular value of the scaled normal matrix dropped
   pure subroutine gn_decrease(jac, r, drop, step)
      real(dp), intent(in) :: jac(:, :), r(:)
      real(dp), intent(out) :: drop
      real(dp), intent(out), optional :: step(:)
      real(dp) :: a(size(jac, 2), size(jac, 2)), v(size(jac, 2), size(jac, 2)), s(size(jac, 2))
      real(dp) :: g(size(jac, 2)), d(size(jac, 2)), c(size(jac, 2))
      integer :: j, info
      a = mat_mul(transpose(jac), jac)
      g = mat_mul(transpose(jac), r)
      do j = 1, size(d)
         d(j) = sqrt(a(j, j))
         if (d(j) <= 0.0_dp) d(j) = 1.0_dp
      end do
      do j = 1, size(d)
         a(:, j) = a(:, j)/(d*d(j))
      end do
      g = g/d
      call svd(a, s, v, info)
      drop = 0.0_dp
      c = 0.0_dp
      if (info /= 0) return
      do j = 1, size(s)
         if (s(j) <= 1.0e-10_dp*s(1)) exit
         c = c + v(:, j)*dot_product(v(:, j), g)/s(j)
         drop = drop + dot_product(v(:, j), g)**2/s(j)
      end do
      if (present(step)) step = -c/d
   end subroutine gn_decrease

   !> Which parameters of effect k are free on the tests `tests` (per-test parameters of the
   !> other tests stay 0); screening leaves the rate of the second back stress fixed
   pure function free_params(ep, tests, screening) result(free)
      type(effect_problem), intent(in) :: ep
      integer, intent(in) :: tests(:)
      logical, intent(in) :: screening
      logical :: free(size(ep%p0))
      type(effect_info) :: cat(n_effects)
      integer :: nt, j, i
      cat = effect_catalogue(1.0_dp)
      nt = size(ep%prob%targets)
      free = .true.
      if (cat(ep%k)%sharing == param_per_test) then
         do j = 1, size(free)
            i = mod(j - 1, nt) + 1
            free(j) = any(tests == i)
         end do
      else if (screening) then
         free = free .and. cat(ep%k)%screened(1:size(free))
      end if
      free = free .and. ep%pacts
   end function free_params

   !> The effect's parameters at the low end of its realistic range (info%low), as changes
   !> of ep%p0 (physical units; columns: one per parameter group with a low end, the other
   !> group at p0): a per-test parameter at the low end in every test of `tests` (drift: the
   !> low end's strain over each test's duration), the second back stress's H3 at the low
   !> end of its saturation H3/gamma3 at p0's gamma3
   pure function low_end_deltas(ep, info, tests) result(d)
      type(effect_problem), intent(in) :: ep
      type(effect_info), intent(in) :: info
      integer, intent(in) :: tests(:)
      real(dp), allocatable :: d(:, :)
      integer :: g, i, j, nt
      nt = size(ep%prob%targets)
      allocate (d(size(ep%p0), 0))
      do g = 1, min(2, info%nparam)
         if (info%low(g) <= 0.0_dp) cycle
         ! A group that does not act on the model (scatter's drag factor on a model without
         ! one) has no signal to find
         if (info%sharing == param_per_test) then
            if (.not. any(ep%pacts((g - 1)*nt + 1:g*nt))) cycle
         else if (.not. ep%pacts(g)) then
            cycle
         end if
         d = reshape([d, spread(0.0_dp, 1, size(ep%p0))], [size(ep%p0), size(d, 2) + 1])
         if (info%sharing == param_per_test) then
            do i = 1, size(tests)
               j = (g - 1)*nt + tests(i)
               d(j, size(d, 2)) = info%low(g)
               if (ep%k == 9) then
                  associate (t => ep%prob%targets(tests(i))%t)
                     d(j, size(d, 2)) = info%low(g)/max(maxval(t) - minval(t), tiny(1.0_dp))
                  end associate
               end if
            end do
         else
            d(g, size(d, 2)) = info%low(g)
            if (ep%k == 8) d(g, size(d, 2)) = info%low(g)*ep%p0(2)
         end if
      end do
   end function low_end_deltas

   !> Starts xs (columns: x of ep, inside lo..hi) of an effect fitted with the constants
   !> fixed from the parameters ps (columns), each once: a start that the search box moves
   !> onto an earlier one (minus the low end of an effect that cannot be negative) is left
   !> out. ep%p0 is set to each column in turn and left as it was.
   pure subroutine distinct_starts(ep, ps, lo, hi, xs)
      type(effect_problem), intent(inout) :: ep
      real(dp), intent(in) :: ps(:, :), lo(:), hi(:)
      real(dp), allocatable, intent(out) :: xs(:, :)
      real(dp), allocatable :: x(:), p0(:)
      integer :: j
      p0 = ep%p0
      allocate (xs(size(lo), 0))
      do j = 1, size(ps, 2)
         ep%p0 = ps(:, j)
         x = min(max(ep%start(), lo), hi)
         if (any(count(spread(x, 2, size(xs, 2)) /= xs, 1) == 0)) cycle
         xs = reshape([xs, x], [size(x), size(xs, 2) + 1])
      end do
      ep%p0 = p0
   end subroutine distinct_starts

   !> An effect's parameters p0 and p0 plus and minus each column of d (its low ends,
   !> low_end_deltas), as columns, p0 first: where an effect is fitted to one test with the
   !> constants fixed, a search from zero alone can stay near zero (a temperature offset of
   !> -5 K on one specimen, refitted from zero, stayed at -0.004 K)
   pure function low_end_starts(p0, d) result(ps)
      real(dp), intent(in) :: p0(:), d(:, :)
      real(dp), allocatable :: ps(:, :)
      ps = reshape([p0, spread(p0, 2, size(d, 2)) + d, spread(p0, 2, size(d, 2)) - d], &
                   [size(p0), 1 + 2*size(d, 2)])
   end function low_end_starts

   !> Difference steps (units of the problem's x) of the screening's Jacobian at the effect's
   !> zero: a tenth of the low end of each parameter's realistic range (low_end_deltas), at
   !> least h. The score test asks whether an effect of realistic size lowers the objective;
   !> over the constants' step h (1e-3 of the parameter's unit) the lag's column differenced
   !> the integrator's error along a 1 ms transient at each corner more than the lag's
   !> signal, and a lag of 0.10 s that lowered the objective from 3.79 to 1.17 screened at
   !> nothing. Parameters without a low end (a rate held at its default) keep h.
   pure function screening_steps(ep, info, tests, h) result(steps)
      type(effect_problem), intent(in) :: ep
      type(effect_info), intent(in) :: info
      integer, intent(in) :: tests(:)
      real(dp), intent(in) :: h
      real(dp), allocatable :: steps(:)
      real(dp), parameter :: share = 0.1_dp
      real(dp), allocatable :: d(:, :), pstep(:)
      integer :: nc
      nc = ep%nx() - count(ep%pfree)
      d = low_end_deltas(ep, info, tests)
      allocate (pstep(size(ep%p0)))
      pstep = 0.0_dp
      if (size(d, 2) > 0) pstep = share*maxval(abs(d), 2)/ep%pscale
      steps = [spread(h, 1, nc), max(h, pack(pstep, ep%pfree))]
   end function screening_steps

   !> Number of residuals (points) of each of the tests, in the problem's order of residuals
   pure function test_sizes(prob, tests) result(n)
      type(fit_problem), intent(in) :: prob
      integer, intent(in) :: tests(:)
      integer :: n(size(tests))
      integer :: i
      do i = 1, size(tests)
         n(i) = size(prob%targets(tests(i))%t)
      end do
   end function test_sizes

   !> Sums of squares of r over its consecutive blocks of n(1), n(2), ... residuals
   pure function block_sums(n, r) result(s)
      integer, intent(in) :: n(:)
      real(dp), intent(in) :: r(:)
      real(dp) :: s(size(n))
      integer :: i, k0
      k0 = 0
      do i = 1, size(n)
         s(i) = sum(r(k0 + 1:k0 + n(i))**2)
         k0 = k0 + n(i)
      end do
   end function block_sums

   !> Power of the significance rule (BIC falls by more than bic_margin on nres residuals
   !> with df parameters more) against a signal of expected chi-square lambda: the tail of
   !> the noncentral chi-square beyond df ln(nres) + bic_margin
   elemental real(dp) function bic_power(lambda, df, nres) result(p)
      real(dp), intent(in) :: lambda
      integer, intent(in) :: df, nres
      p = ncx2_sf(df*log_dp(real(max(nres, 2), dp)) + bic_margin, real(max(df, 1), dp), lambda)
   end function bic_power

   !> The expected chi-square (noncentrality) at which the rule of bic_power (df parameters,
   !> nres residuals) has the given power (0 < power < 1), by bisection on its logarithm
   pure real(dp) function power_lambda(power, df, nres) result(lambda)
      real(dp), intent(in) :: power
      integer, intent(in) :: df, nres
      real(dp) :: lo, hi
      integer :: it
      lo = 1.0e-6_dp
      hi = 1.0e6_dp
      do it = 1, 80
         lambda = sqrt(lo*hi)
         if (bic_power(lambda, df, nres) < power) then
            lo = lambda
         else
            hi = lambda
         end if
      end do
      lambda = sqrt(lo*hi)
   end function power_lambda

   !> Starts (a, b: columns) of a fit of the saturating softening: zero at the rate
   !> soften_rate0, then a tenth of the physical limit of a with either sign (softening,
   !> hardening) at rates a decade below, at and a decade above it (its rate has no gradient
   !> at a = 0, and from one rate a fit can stay in the basin of another)
   pure function softening_starts(info) result(ps)
      type(effect_info), intent(in) :: info
      real(dp) :: ps(2, 7)
      integer :: j
      ps(:, 1) = [0.0_dp, soften_rate0]
      do j = 0, 5
         ps(:, j + 2) = [merge(1.0_dp, -1.0_dp, mod(j, 2) == 0)*0.1_dp*info%plausible(1), &
                         soften_rate0*10.0_dp**(j/2 - 1)]
      end do
   end function softening_starts

   !> Starts (H3 in the stress unit, gamma3: columns) of a fit of the second back stress: near
   !> zero (saturation H3/gamma3 of 5e-5 of the peak) at the rate gamma3, then saturations of
   !> 3 and 10 % of the peak at each rate of b2_rates times it (inside H3's search box, which
   !> reaches the peak's saturation at gamma3's box end). Its rate has no gradient
   !> near zero, and a fit stays in the basin of the rate it starts from: on the Alloy 617
   !> tests every start at gamma3 = 200 ended near the baseline (dBIC -76), starts at 2000
   !> reached dBIC -2346 (gamma3 held there) and, every test fitted, gamma3 = 3800; on one
   !> specimen a single start ended at 48 % of a gap the injected back stress removes whole;
   !> with rates up to ten times it, 12 of 14 held-out LCF tests with gamma3 1000-5000 named
   !> the back stress (misses at 4474 and 4898), up to fifty times 13 of 14
   pure function backstress2_starts(peak, gamma3) result(ps)
      !> peak stress of the tests (stress unit)
      real(dp), intent(in) :: peak
      !> the screening's recovery rate (-)
      real(dp), intent(in) :: gamma3
      real(dp) :: ps(2, 1 + 2*size(b2_rates))
      real(dp), parameter :: sats(2) = [0.03_dp, 0.1_dp]
      real(dp) :: g3
      integer :: j, nr
      nr = size(b2_rates)
      ps(:, 1) = [0.01_dp*peak, gamma3]
      do j = 1, 2*nr
         g3 = gamma3*b2_rates(mod(j - 1, nr) + 1)
         ps(:, j + 1) = [sats((j - 1)/nr + 1)*peak*g3, g3]
      end do
   end function backstress2_starts

   !> The first start of an effect with a rate, the saturating softening (k = 7) or the second
   !> back stress (k = 8): the first column of softening_starts or backstress2_starts
   pure function rate_effect_start(info, k, peak, gamma3) result(p0)
      type(effect_info), intent(in) :: info
      !> catalogue effect, 7 or 8
      integer, intent(in) :: k
      !> peak stress of the tests (stress unit); the screening's recovery rate (-)
      real(dp), intent(in) :: peak, gamma3
      real(dp) :: p0(2)
      real(dp), allocatable :: ps(:, :)
      if (k == 8) then
         ps = backstress2_starts(peak, gamma3)
      else
         ps = softening_starts(info)
      end if
      p0 = ps(:, 1)
   end function rate_effect_start

   !> Share of the drag the saturating softening a, b (catalogue effect 7) takes away by the
   !> end of the tests of ep at x: |a|(1 - exp(-b p_end)), p_end the largest accumulated
   !> inelastic strain a test reaches (the sum of its inelastic strain's changes between
   !> output points). What the data measure: where b p_end << 1 they give a*b, not a, and a
   !> fitted a beyond its limit is an extrapolation past the tests
   function softening_reached(ep, x, a, b) result(share)
      type(effect_problem), intent(in) :: ep
      real(dp), intent(in) :: x(:), a, b
      real(dp) :: share
      real(dp), allocatable :: r(:), ein(:)
      real(dp) :: p_end
      integer :: it, k0, n
      logical :: ok
      allocate (r(ep%nres()), ein(ep%nres()))
      call ep%residual_at(x, r, ok, eps_in=ein)
      ! a test that fails to simulate: judged by a itself
      share = abs(a)
      if (.not. ok) return
      p_end = 0.0_dp
      k0 = 0
      do it = 1, size(ep%tests)
         n = size(ep%prob%targets(ep%tests(it))%t)
         if (n > 0) p_end = max(p_end, abs(ein(k0 + 1)) + sum(abs(ein(k0 + 2:k0 + n) - ein(k0 + 1:k0 + n - 1))))
         k0 = k0 + n
      end do
      share = abs(a)*(1.0_dp - exp_dp(-b*p_end))
   end function softening_reached

   !> What beyond_limit judges a softening and a second back stress by, from the effect's
   !> parameters p (a, b or H3, gamma3 first) at the search point x of ep: the softening's
   !> reach (softening_reached) and the back stress's saturation |H3/gamma3| over the peak
   !> stress; 0 where they do not apply
   subroutine limit_measures(info, ep, x, p, peak, reach, saturation)
      type(effect_info), intent(in) :: info
      type(effect_problem), intent(in) :: ep
      real(dp), intent(in) :: x(:), p(:), peak
      real(dp), intent(out) :: reach, saturation
      reach = 0.0_dp
      saturation = 0.0_dp
      if (size(p) < 2) return
      if (info%name == 'softening') reach = softening_reached(ep, x, p(1), p(2))
      if (info%name == 'backstress2' .and. p(2) > 0.0_dp) then
         saturation = abs(p(1)/p(2))/peak
      else if (info%name == 'backstress2' .and. p(1) /= 0.0_dp) then
         ! gamma3 at 0: a back stress that hardens without end never saturates (a fit of a
         ! specimen's difference to H3 = 866 MPa, gamma3 = 0 passed as within the peak)
         saturation = huge(1.0_dp)
      end if
   end subroutine limit_measures

   !> Whether an effect's magnitude lies below what the diagnosis resolves at 95 %: every
   !> free parameter with a low end has both ends of its interval bounded and inside
   !> resolved_share of it, and at least one has a low end. The low ends are those of the
   !> ranges the diagnosis is validated over; a quarter of them is about a thermocouple's
   !> tolerance (1.25 K), the sampling interval of the Alloy 617 tests (25 ms), 0.5 % of the
   !> peak stress. A temperature offset of -0.65 K [-0.92, -0.35] lowered a specimen's BIC by
   !> 11.2 where a drift its tests could not show had been put: not a finding about it
   pure logical function below_resolved(p_lo, p_hi, unbounded, low) result(below)
      !> The free parameters' 95 % intervals
      real(dp), intent(in) :: p_lo(:), p_hi(:)
      !> An end of the interval that the data do not bound
      logical, intent(in) :: unbounded(:)
      !> Each free parameter's low end (its magnitude; 0: none)
      real(dp), intent(in) :: low(:)
      integer :: g
      below = .false.
      do g = 1, size(low)
         if (.not. low(g) > 0.0_dp) cycle
         if (unbounded(g) .or. .not. (abs(p_lo(g)) < resolved_share*low(g) .and. &
                                      abs(p_hi(g)) < resolved_share*low(g))) then
            below = .false.
            return
         end if
         below = .true.
      end do
   end function below_resolved

   !> The ratio of a fitted value to its limit that the plausibility judgement uses: at the
   !> end of the value's 95 % interval nearest zero where the interval is finite and of one
   !> sign, else (a value the data leave undetermined) the fitted ratio itself
   pure real(dp) function ratio_beyond_doubt(ratio, p, p_lo, p_hi) result(r)
      real(dp), intent(in) :: ratio        !< |p|/limit
      real(dp), intent(in) :: p, p_lo, p_hi  !< fitted value and its interval
      r = ratio
      if (p_lo*p_hi > 0.0_dp .and. ieee_is_finite(p_lo) .and. ieee_is_finite(p_hi)) &
         r = ratio*min(abs(p_lo), abs(p_hi))/abs(p)
   end function ratio_beyond_doubt

   !> How far an effect's fitted magnitude lies beyond its physical limit beyond doubt (above 1:
   !> implausible), as the held-out and the per-specimen diagnoses both judge it: a softening
   !> by the share of the drag it takes away within the test (reach, see softening_reached);
   !> any other effect by its largest free parameter against that parameter's limit, at the
   !> end of its 95 % interval nearest zero where the data close the interval
   !> (ratio_beyond_doubt), by its value where they leave an end open; a second back stress
   !> also by its saturation H3/gamma3 against the peak stress (saturation, that ratio)
   pure real(dp) function beyond_limit(info, grp, p, p_lo, p_hi, unbounded, reach, saturation) result(sure)
      type(effect_info), intent(in) :: info
      !> Each free parameter's place in the catalogue's list of the effect's parameters
      integer, intent(in) :: grp(:)
      !> The free parameters and their 95 % intervals
      real(dp), intent(in) :: p(:), p_lo(:), p_hi(:)
      !> An end of the interval that the data do not bound
      logical, intent(in) :: unbounded(:)
      !> The softening's reach over its limit's quantity, the back stress's |H3/gamma3|/peak
      real(dp), intent(in) :: reach, saturation
      real(dp) :: ratio
      integer :: g
      if (info%name == 'softening') then
         sure = reach/info%plausible(1)
         return
      end if
      sure = 0.0_dp
      do g = 1, size(p)
         if (info%plausible(grp(g)) >= huge(1.0_dp)) cycle
         ratio = abs(p(g))/info%plausible(grp(g))
         if (g <= size(p_lo) .and. .not. unbounded(g)) ratio = ratio_beyond_doubt(ratio, p(g), p_lo(g), p_hi(g))
         ! (a magnitude that is not a number is beyond its limit: max would drop it)
         if (.not. ratio <= sure) sure = ratio
      end do
      if (info%name == 'backstress2') sure = max(sure, saturation)
   end function beyond_limit

   !> A per-test effect's values fitted to the held-out tests (those free in held_free, of
   !> the parameters p of every test, names the tests') against their physical limits: the
   !> largest (worst, 0 when none has a limit) and which, parameter and test (worst_what),
   !> for the report beside the fit tests' largest (a drift named 0.4 of its limit on the
   !> fit tests had needed more than its limit on a held-out test). Plausibility stays with
   !> the fit tests' values and their intervals: a held-out value is fitted with the
   !> constants fixed at the fit tests', carries their error, and has no interval that holds
   !> it (a temperature offset of -24.8 K, 0.99 of its limit, came out at 32 K on a held-out
   !> LCF test).
   pure subroutine judge_held_values(info, names, held_free, p, worst, worst_what)
      type(effect_info), intent(in) :: info
      character(len=*), intent(in) :: names(:)
      logical, intent(in) :: held_free(:)
      real(dp), intent(in) :: p(:)
      real(dp), intent(out) :: worst
      character(len=:), allocatable, intent(out) :: worst_what
      integer :: g, j, nt, i
      real(dp) :: ratio
      worst = 0.0_dp
      worst_what = ''
      if (info%sharing /= param_per_test) return
      nt = size(names)
      do g = 1, info%nparam
         if (info%plausible(g) >= huge(1.0_dp)) cycle
         do j = 1, nt
            i = (g - 1)*nt + j
            if (i > min(size(held_free), size(p))) cycle
            if (.not. held_free(i)) cycle
            ratio = abs(p(i))/info%plausible(g)
            if (ratio > worst .or. len(worst_what) == 0) then
               worst = ratio
               worst_what = trim(info%pname(g))//' '//trim(names(j))
            end if
         end do
      end do
   end subroutine judge_held_values

   !> The parameter of a global effect that screening holds at its start (no gradient at
   !> zero: the second back stress's gamma3, the softening's b), when it is the last of its
   !> parameters (the refit's layout puts it last); 0 when there is none
   pure integer function held_rate(info) result(j)
      type(effect_info), intent(in) :: info
      j = 0
      if (info%sharing /= param_global .or. info%nparam < 2) return
      if (count(.not. info%screened(1:info%nparam)) /= 1) return
      if (.not. info%screened(info%nparam)) j = info%nparam
   end function held_rate

   !> The fit of the constants with effect k on the fit tests, from the baseline constants
   !> and zero effect (the second back stress from a small modulus, so that its rate has a
   !> gradient; the softening at the rate soften_rate0)
   subroutine effect_fit(ctx, k, ep, held, rate)
      type(diagnose_context), intent(in) :: ctx
      !> Catalogue effect
      integer, intent(in) :: k
      type(effect_problem), intent(out) :: ep
      !> The rates that screening holds (the parameters without a gradient at zero: the
      !> second back stress's gamma3, the softening's b) held at their start (see refit)
      logical, intent(in), optional :: held
      !> That start, where positive (see effect_outcome's rate_start); else the screening's
      real(dp), intent(in), optional :: rate
      call new_effect_problem(ctx%prob, ctx%ifit, k, ctx%eff_base, ctx%peak, ep)
      ep%pfree = free_params(ep, ctx%ifit, .false.)
      if (k == 7 .or. k == 8) ep%p0 = rate_effect_start(ctx%cat(k), k, ctx%peak, ctx%opts%gamma3)
      if (held_rate(ctx%cat(k)) == 0) return
      if (present(rate)) then
         if (rate > 0.0_dp) ep%p0(held_rate(ctx%cat(k))) = rate
      end if
      if (present(held)) then
         if (held) ep%pfree(held_rate(ctx%cat(k))) = .false.
      end if
   end subroutine effect_fit

   !> n Latin-hypercube points of the constants (log10) over the &fit multi-start box,
   !> drawn with the &fit seed
   function global_points(cfg, prob, n) result(xs)
      type(run_config), intent(in) :: cfg
      type(fit_problem), intent(in) :: prob
      integer, intent(in) :: n
      real(dp), allocatable :: xs(:, :)
      type(rng_type) :: rng
      real(dp), allocatable :: u(:, :), blo(:), bhi(:)
      integer :: j
      allocate (xs(size(prob%idx), n))
      if (n == 0) return
      blo = log10_dp(cfg%fit%box_lower(prob%idx))
      bhi = log10_dp(cfg%fit%box_upper(prob%idx))
      call rng%seed(cfg%fit%seed)
      call latin_hypercube(rng, size(prob%idx), n, u)
      do j = 1, n
         xs(:, j) = blo + u(:, j)*(bhi - blo)
      end do
   end function global_points

   !> Levenberg-Marquardt (100 steps) from every column of xs; opt becomes the lowest end
   !> point when it is lower than opt already is. A start where the model fails is passed
   !> over (its fs: huge).
   subroutine best_of_starts(ep, xs, lo, hi, h, max_evals, opt, nevals, fs, over_ranks, each, ran_ok)
      type(effect_problem), intent(inout) :: ep
      real(dp), intent(in) :: xs(:, :), lo(:), hi(:), h
      integer, intent(in) :: max_evals
      type(optimum_type), intent(inout) :: opt
      integer, intent(inout) :: nevals
      !> Objective at the end of each start
      real(dp), intent(out), optional :: fs(:)
      !> Spread the starts over the MPI ranks (every rank calls this with the same starts);
      !> the outcome is that of one process
      logical, intent(in), optional :: over_ranks
      !> Each start's outcome, and whether it ran to an outcome (false: passed over)
      type(optimum_type), intent(out), optional :: each(:)
      logical, intent(out), optional :: ran_ok(:)
      type(optimum_type), allocatable :: alts(:)
      type(effect_problem), allocatable :: eps(:)
      type(error_type), allocatable :: error
      logical, allocatable :: ok(:), ran(:)
      integer, allocatable :: owner(:)
      type(task_deal) :: deal
      logical :: spread
      integer :: j, n0
      spread = .false.
      if (present(over_ranks)) spread = over_ranks .and. n_ranks() > 1
      if (present(fs)) fs = huge(1.0_dp)
      allocate (alts(size(xs, 2)), ok(size(xs, 2)), ran(size(xs, 2)))
      ok = .false.
      n0 = ep%nevals
      ran = .false.
      if (.not. spread .and. size(xs, 2) > 1 .and. omp_get_max_threads() > 1) then
         ! The starts side by side on this process's threads, each on a problem of its own:
         ! tasks, whose difference Jacobians are tasks too (see ep_residuals), so that no
         ! thread idles while one start's line search runs alone. Each start's numbers are
         ! those of the starts one after the other.
         allocate (eps(size(xs, 2)))
         !$omp parallel
         !$omp single
         do j = 1, size(xs, 2)
            !$omp task firstprivate(j)
            call one_start(j)
            !$omp end task
         end do
         !$omp end single
         !$omp end parallel
         ep%nevals = n0 + sum(eps%nevals - n0)
         ran = .true.
      else
         ! Spread: each start to the next rank that is free
         call deal%open(1, size(xs, 2), alone=.not. spread)
         do
            j = deal%take()
            if (j == 0) exit
            ran(j) = .true.
            call levenberg_marquardt(ep, min(max(xs(:, j), lo), hi), lo, hi, h, lm_ftol, lm_itermax, &
                                     max_evals, alts(j), error, updates=lm_updates)
            if (allocated(error)) then
               deallocate (error)
               cycle
            end if
            ok(j) = .true.
         end do
         call deal%close()
      end if
      if (spread) then
         owner = ranks_that_ran(ran)
         do j = 1, size(xs, 2)
            call share_optimum(alts(j), ok(j), owner(j))
         end do
         ep%nevals = n0 + sum_over_ranks(ep%nevals - n0)
      end if
      call take_starts(alts, ok, opt, nevals, fs)
      if (present(each)) each = alts
      if (present(ran_ok)) ran_ok = ok

   contains

      !> Start j on a copy of the problem (a start that fails is passed over)
      subroutine one_start(j)
         integer, intent(in) :: j
         type(error_type), allocatable :: err
         eps(j) = ep
         call levenberg_marquardt(eps(j), min(max(xs(:, j), lo), hi), lo, hi, h, lm_ftol, lm_itermax, &
                                  max_evals, alts(j), err, updates=lm_updates)
         ok(j) = .not. allocated(err)
      end subroutine one_start
   end subroutine best_of_starts

   !> The starts' outcomes alts (those with ok) in their order, as one process takes them:
   !> opt becomes the lowest when lower than it is; their evaluations added to nevals, their
   !> objectives in fs
   pure subroutine take_starts(alts, ok, opt, nevals, fs)
      type(optimum_type), intent(in) :: alts(:)
      logical, intent(in) :: ok(:)
      type(optimum_type), intent(inout) :: opt
      integer, intent(inout) :: nevals
      real(dp), intent(inout), optional :: fs(:)
      integer :: j
      do j = 1, size(alts)
         if (.not. ok(j)) cycle
         nevals = nevals + alts(j)%nevals
         if (present(fs)) fs(j) = alts(j)%f
         if (alts(j)%f < opt%f) opt = alts(j)
      end do
   end subroutine take_starts

   !> A start's outcome from the rank that ran it to every rank
   subroutine share_optimum(o, ok, from)
      type(optimum_type), intent(inout) :: o
      logical, intent(inout) :: ok
      integer, intent(in) :: from
      integer, allocatable :: ints(:)
      real(dp), allocatable :: reals(:)
      character(len=:), allocatable :: reason
      if (this_rank() == from) then
         ints = [merge(1, 0, ok), o%nevals, o%iterations]
         reals = [real(dp) ::]
         reason = ''
         if (ok) then
            reals = [o%f, o%x]
            if (allocated(o%reason)) reason = o%reason
         end if
      end if
      call share(ints, from)
      call share(reals, from)
      call share(reason, from)
      if (this_rank() == from) return
      ok = ints(1) == 1
      if (.not. ok) return
      o%nevals = ints(2)
      o%iterations = ints(3)
      o%f = reals(1)
      o%x = reals(2:)
      o%reason = reason
   end subroutine share_optimum

   !> The residuals r and their forward-difference Jacobian jac at x (step h), simulated at
   !> the tight tolerances tight_tol
   subroutine tight_jacobian(ep, x, h, r, jac, ok)
      type(effect_problem), intent(inout) :: ep
      real(dp), intent(in) :: x(:), h
      real(dp), allocatable, intent(out) :: r(:), jac(:, :)
      logical, intent(out) :: ok
      real(dp) :: tol(2)
      tol = [ep%prob%cfg%solver%rtol, ep%prob%cfg%solver%atol_strain]
      ep%prob%cfg%solver%rtol = tight_tol(1)
      ep%prob%cfg%solver%atol_strain = tight_tol(2)
      call jacobian(ep, x, h, r, jac, ok)
      ep%prob%cfg%solver%rtol = tol(1)
      ep%prob%cfg%solver%atol_strain = tol(2)
   end subroutine tight_jacobian

   !> Covariance of the parameters of a least-squares fit from the Jacobian jf of its
   !> residuals and their noise variances nv: the sandwich (Jf'Jf)^+ Jf' N Jf (Jf'Jf)^+
   pure function sandwich_covariance(jf, nv) result(cov)
      real(dp), intent(in) :: jf(:, :), nv(:)
      real(dp), allocatable :: cov(:, :)
      real(dp), allocatable :: ai(:, :), jn(:, :)
      integer :: j
      ai = pseudo_inverse(mat_mul(transpose(jf), jf))
      jn = jf
      do j = 1, size(jf, 2)
         jn(:, j) = jf(:, j)*sqrt(nv)
      end do
      cov = mat_mul(ai, mat_mul(mat_mul(transpose(jn), jn), ai))
   end function sandwich_covariance

   !> The noise standard deviation of each test tests(k) of prob (response unit) from the
   !> second differences (noise_sd) of its residual against ysim, the simulated response at
   !> its compared points (the tests' points in that order); the points without data (the
   !> peaks of a peaks target) left out. The model takes out the response's own curvature,
   !> which second differences of the data alone read as noise where the sampling is coarse
   !> (thesis LCF at 0.5 s with 0.5 % noise: 12 % more than the noise, the residual's 0.0 %)
   !> lag: the second differences taken that many samples apart (see noise_sd)
   pure function residual_noise(prob, tests, ysim) result(sd)
      type(fit_problem), intent(in) :: prob
      integer, intent(in) :: tests(:)
      real(dp), intent(in) :: ysim(:)    !< response unit
      real(dp) :: sd(size(tests))
      real(dp), allocatable :: r(:)
      integer :: k, k0
      k0 = 0
      do k = 1, size(tests)
         call data_residual(prob, tests(k), ysim, k0, r)
         sd(k) = noise_sd(r)
      end do
   end function residual_noise

   !> Test it of prob's residual at its data points (the peaks of a peaks target left out)
   !> against ysim, the simulated response of the tests' points from k0 + 1 on; k0 moves past
   !> the test's points
   pure subroutine data_residual(prob, it, ysim, k0, r)
      type(fit_problem), intent(in) :: prob
      integer, intent(in) :: it
      real(dp), intent(in) :: ysim(:)
      integer, intent(inout) :: k0
      real(dp), allocatable, intent(out) :: r(:)
      integer :: n
      associate (tg => prob%targets(it), test => prob%cfg%tests(it))
         n = size(tg%t)
         r = tg%y_ex - ysim(k0 + 1:k0 + n)
         if (test%has_peaks()) r = pack(r, test%point_kind == 0)
         k0 = k0 + n
      end associate
   end subroutine data_residual

   !> For each test tests(k), how far its residual's noise is from independent: the noise sd
   !> from second differences corr_lag samples apart over that from neighbours (1 for
   !> independent noise: the thesis tests with 1 % noise give 1.00 to 1.05; measured Alloy 617
   !> cycles 3 to 5, their noise correlated over samples). 0 where the test has too few points
   pure function noise_correlation(prob, tests, ysim) result(ratio)
      type(fit_problem), intent(in) :: prob
      integer, intent(in) :: tests(:)
      real(dp), intent(in) :: ysim(:)    !< response unit
      real(dp) :: ratio(size(tests))
      real(dp), allocatable :: r(:)
      integer :: k, k0
      k0 = 0
      do k = 1, size(tests)
         call data_residual(prob, tests(k), ysim, k0, r)
         ratio(k) = noise_lag_ratio(r, corr_lag)
      end do
   end function noise_correlation

   !> The noise variance of each residual of the tests tests of prob (objective units, test
   !> after test in that order) for noises of standard deviation sd(k) in test tests(k)'s
   !> response
   pure function noise_variance(prob, tests, sd) result(nv)
      type(fit_problem), intent(in) :: prob
      integer, intent(in) :: tests(:)
      real(dp), intent(in) :: sd(:)
      real(dp), allocatable :: nv(:)
      integer :: n, k
      allocate (nv(0))
      do k = 1, size(tests)
         associate (tg => prob%targets(tests(k)))
            n = size(tg%t)
            nv = [nv, (sd(k)*test_residuals(prob%cfg%fit%objective, spread(1.0_dp, 1, n), &
                                            spread(0.0_dp, 1, n), tg%w, tg%y_ex_max))**2]
         end associate
      end do
   end function noise_variance

   !> Pseudo-inverse of a symmetric positive semi-definite matrix (directions below 1e-12 of
   !> the largest singular value dropped), after scaling to a unit diagonal
   pure function pseudo_inverse(a) result(ai)
      real(dp), intent(in) :: a(:, :)
      real(dp) :: ai(size(a, 1), size(a, 2))
      real(dp) :: b(size(a, 1), size(a, 2)), v(size(a, 1), size(a, 2)), s(size(a, 1)), d(size(a, 1))
      integer :: j, info
      do j = 1, size(d)
         d(j) = sqrt(max(a(j, j), tiny(1.0_dp)))
      end do
      do j = 1, size(d)
         b(:, j) = a(:, j)/(d*d(j))
      end do
      call svd(b, s, v, info)
      ai = 0.0_dp
      if (info /= 0) return
      do j = 1, size(s)
         if (s(j) <= 1.0e-12_dp*s(1)) exit
         ai = ai + spread(v(:, j), 2, size(s))*spread(v(:, j), 1, size(s))/s(j)
      end do
      do j = 1, size(d)
         ai(:, j) = ai(:, j)/(d*d(j))
      end do
   end function pseudo_inverse

   !> Which components of x lie at a bound (within 1e-6, log10 units for the constants, as
   !> usharp_identify judges them): -1 at the lower, 1 at the upper, 0 at neither. A fit
   !> that ends there has run away rather than converged, and which end says which way. A
   !> search's steps are projected onto the box, so one that ran away ends on the bound; a
   !> tolerance of a share of the box (1e-3 of it had called C2 at its bound 1.5 % inside
   !> it) names converged constants.
   pure function at_bound(x, lo, hi) result(side)
      real(dp), intent(in) :: x(:), lo(:), hi(:)
      integer :: side(size(x))
      side = 0
      where (x >= hi - bound_tol) side = 1
      where (x <= lo + bound_tol) side = -1
   end function at_bound

   !> Which effect parameters x lie at an outer end of their search box [lo, hi] (within 1e-6
   !> of its width): at hi, or at lo where lo is negative. A lower end of zero is the physical
   !> bound of a parameter that cannot be negative, a value there a finding, not a runaway.
   !> -1 at the lower end, 1 at the upper, 0 at neither.
   pure function at_box_end(x, lo, hi) result(side)
      real(dp), intent(in) :: x(:), lo(:), hi(:)
      integer :: side(size(x))
      side = 0
      where (x >= hi - 1.0e-6_dp*(hi - lo)) side = 1
      where (lo < 0.0_dp .and. x <= lo + 1.0e-6_dp*(hi - lo)) side = -1
   end function at_box_end
end module usharp_diagnose_numerics
