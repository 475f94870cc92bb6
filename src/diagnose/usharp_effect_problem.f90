!> A fit problem with one catalogue effect switched on: the weighted residuals of a chosen set
!> of tests as a function of x = (log10 of the fitted constants, when they are free; the free
!> effect parameters divided by their scale). With effect 0 it is the plain model through the
!> extended integrator, so that fits with and without an effect differ only by the effect.
module usharp_effect_problem
   use usharp_kinds, only: dp
   use usharp_math, only: log10_dp, pow10_dp
   use usharp_error, only: error_type
   use usharp_model, only: model_type
   use usharp_effects, only: test_effects, effect_info, effect_catalogue, effects_of, &
                             effect_model, effect_nparams, n_effects, param_per_test, effect_acts
   use usharp_effect_values, only: effect_reals
   use usharp_objective, only: fit_problem, test_residuals, simulated
   use usharp_optimiser, only: least_squares_type
   use usharp_simulation, only: sim_result, solver_options
   use usharp_history, only: history_type, control_strain, control_stress
   use usharp_cvode_driver, only: simulate_cvode
   use usharp_rosenbrock_driver, only: simulate_rosenbrock
   use omp_lib, only: omp_in_parallel
   implicit none
   private

   public :: effect_problem, new_effect_problem, simulate_effect

   !> The objective of a point whose simulation failed: far above any objective of a test,
   !> so that a search turns away from it
   real(dp), parameter, public :: failed_objective = 2.0e10_dp

   !> Residuals of the tests `tests` with effect k (0: none)
   type, extends(least_squares_type) :: effect_problem
      type(fit_problem) :: prob                !< tests, targets, model, solver
      integer, allocatable :: tests(:)         !< indices of the tests in the residual
      integer :: k = 0                         !< catalogue effect (0: none)
      !> effect k acts through the extended model's p and R2: every point carries them
      logical :: states = .false.
      logical :: free_constants = .true.       !< the fitted constants are in x
      real(dp), allocatable :: p0(:)           !< effect parameters (physical units, all tests)
      logical, allocatable :: pfree(:)         !< which of them are in x
      !> which of them act on the model (effect_acts): the others stay at zero, never free
      logical, allocatable :: pacts(:)
      real(dp), allocatable :: pscale(:)       !< unit of x for each parameter
      real(dp), allocatable :: pbox(:)         !< half-width of its search box (unit of x)
      logical, allocatable :: pnonneg(:)
      type(test_effects) :: base               !< dlnE_dT, gamma3 held fixed
      !> When > 0, the effect acts on this test (an index into prob's tests) alone, a global
      !> effect's parameters included: one specimen's property beside its replicates
      integer :: effect_test = 0
      !> When allocated, a factor on each test's residuals (prob's tests): a weighting of the
      !> tests against one another
      real(dp), allocatable :: test_scale(:)
      integer :: nevals = 0
      !> Tests simulated (nevals counts points; a test whose rows were copied is not counted)
      integer :: nsims = 0
      !> What each test saw at the last point evaluated on its own (test_inputs), and that
      !> point's residuals: a test that sees the same at a later point takes its rows from
      !> there (see ep_residuals)
      real(dp), allocatable :: seen_last(:, :), r_last(:)
   contains
      procedure :: residuals => ep_residuals
      procedure :: test_inputs => ep_test_inputs
      procedure :: effects_at => ep_effects_at
      procedure :: first_rows => ep_first_rows
      procedure :: nres => ep_nres
      procedure :: eval => ep_eval
      procedure :: nx => ep_nx
      procedure :: start => ep_start
      procedure :: bounds => ep_bounds
      procedure :: unpack => ep_unpack
      procedure :: residual_at => ep_residual_at
   end type effect_problem

contains

   !> Problem for effect k on the tests `tests` of prob; the effect's parameters start at p0
   !> (zero when absent), all free; constants free unless free_constants is false
   subroutine new_effect_problem(prob, tests, k, base, peak, ep, free_constants, p0)
      type(fit_problem), intent(in) :: prob
      integer, intent(in) :: tests(:), k
      type(test_effects), intent(in) :: base
      real(dp), intent(in) :: peak
      type(effect_problem), intent(out) :: ep
      logical, intent(in), optional :: free_constants
      real(dp), intent(in), optional :: p0(:)
      type(effect_info) :: cat(n_effects)
      integer :: np, nt, j, g
      ep%prob = prob
      ep%tests = tests
      ep%k = k
      ep%base = base
      if (present(free_constants)) ep%free_constants = free_constants
      nt = size(prob%targets)
      np = 0
      if (k > 0) then
         cat = effect_catalogue(peak)
         np = effect_nparams(cat(k), nt)
         ep%states = cat(k)%states
      end if
      allocate (ep%p0(np), ep%pfree(np), ep%pscale(np), ep%pbox(np), ep%pnonneg(np), ep%pacts(np))
      ep%p0 = 0.0_dp
      if (present(p0)) ep%p0 = p0
      do j = 1, np
         ! per-test parameters are ordered parameter-major: group g holds nt values
         if (cat(k)%sharing == param_per_test) then
            g = (j - 1)/nt + 1
         else
            g = j
         end if
         ep%pscale(j) = cat(k)%scale(g)
         ep%pbox(j) = cat(k)%box(g)
         ep%pnonneg(j) = cat(k)%nonneg(g)
         ep%pacts(j) = effect_acts(prob%cfg%model, k, g)
      end do
      ep%pfree = ep%pacts
   end subroutine new_effect_problem

   pure integer function ep_nx(self) result(n)
      class(effect_problem), intent(in) :: self
      n = count(self%pfree)
      if (self%free_constants) n = n + size(self%prob%idx)
   end function ep_nx

   pure integer function ep_nres(self) result(m)
      class(effect_problem), intent(in) :: self
      integer :: i
      m = 0
      do i = 1, size(self%tests)
         m = m + size(self%prob%targets(self%tests(i))%t)
      end do
   end function ep_nres

   !> x of the problem's starting point
   pure function ep_start(self) result(x)
      class(effect_problem), intent(in) :: self
      real(dp), allocatable :: x(:)
      integer :: j
      allocate (x(0))
      if (self%free_constants) then
         do j = 1, size(self%prob%idx)
            x = [x, log10_dp(self%prob%cfg%model%get_constant(self%prob%idx(j)))]
         end do
      end if
      x = [x, pack(self%p0/self%pscale, self%pfree)]
   end function ep_start

   !> Bounds of x: the &fit bounds for the constants, each parameter's search box (the
   !> catalogue's, in units of its scale; from zero where it is kept >= 0)
   pure subroutine ep_bounds(self, lo, hi)
      class(effect_problem), intent(in) :: self
      real(dp), allocatable, intent(out) :: lo(:), hi(:)
      real(dp), allocatable :: plo(:), phi(:)
      plo = merge(0.0_dp, -self%pbox, self%pnonneg)
      phi = self%pbox
      allocate (lo(0), hi(0))
      if (self%free_constants) then
         lo = log10_dp(self%prob%cfg%fit%lower(self%prob%idx))
         hi = log10_dp(self%prob%cfg%fit%upper(self%prob%idx))
      end if
      lo = [lo, pack(plo, self%pfree)]
      hi = [hi, pack(phi, self%pfree)]
   end subroutine ep_bounds

   !> Model constants and effect parameters (physical units) of x
   subroutine ep_unpack(self, x, model, p)
      class(effect_problem), intent(in) :: self
      real(dp), intent(in) :: x(:)
      class(model_type), allocatable, intent(out) :: model
      real(dp), allocatable, intent(out) :: p(:)
      integer :: j, k0
      allocate (model, source=self%prob%cfg%model)
      k0 = 0
      if (self%free_constants) then
         do j = 1, size(self%prob%idx)
            call model%set_constant(self%prob%idx(j), pow10_dp(x(j)))
         end do
         k0 = size(self%prob%idx)
      end if
      p = self%p0
      p = unpack(x(k0 + 1:)*pack(self%pscale, self%pfree), self%pfree, p)
   end subroutine ep_unpack

   !> Residuals of the problem's tests at x; ok false on a failure. The tests are simulated
   !> as tasks that an idle thread takes up (the trial points of Levenberg-Marquardt come one
   !> at a time), each alone: the same numbers on any number of threads.
   subroutine ep_residual_at(self, x, r, ok, fitted, strain, eps_in, only)
      class(effect_problem), intent(in) :: self
      real(dp), intent(in) :: x(:)
      !> With `only`: in, the residuals of the other tests (kept); out, those of that test too
      real(dp), intent(inout) :: r(:)
      logical, intent(out) :: ok
      real(dp), intent(out), optional :: fitted(:)  !< the simulated responses
      real(dp), intent(out), optional :: strain(:)  !< the specimen's total strain, -
      real(dp), intent(out), optional :: eps_in(:)  !< its inelastic strain, -
      !> Simulate only this test (an index into the problem's tests)
      integer, intent(in), optional :: only
      class(model_type), allocatable :: model
      type(test_effects), allocatable :: eff(:)
      type(error_type), allocatable :: error
      real(dp), allocatable :: p(:)
      integer, allocatable :: k0(:)
      logical, allocatable :: failed(:)
      integer :: it, ntr
      ok = .false.
      if (.not. present(only)) r = 0.0_dp
      call self%unpack(x, model, p)
      call model%setup(error)
      if (allocated(error)) return
      eff = self%effects_at(p)
      k0 = self%first_rows()
      allocate (failed(size(self%tests)))
      failed = .false.
      ntr = size(self%tests)
      if (present(only)) then
         call one(only)
      else if (omp_in_parallel()) then
         !$omp taskloop grainsize(1) default(shared)
         do it = 1, ntr
            call one(it)
         end do
         !$omp end taskloop
      else
         !$omp parallel do schedule(dynamic) default(shared)
         do it = 1, ntr
            call one(it)
         end do
         !$omp end parallel do
      end if
      ok = .not. any(failed) .and. all(abs(r) < huge(1.0_dp))

   contains

      !> Test it of the problem: its rows of r (and of the optional outputs)
      subroutine one(it)
         integer, intent(in) :: it
         type(error_type), allocatable :: err
         type(sim_result) :: res
         real(dp), allocatable :: ysim(:)
         integer :: i, n
         i = self%tests(it)
         associate (tg => self%prob%targets(i), test => self%prob%cfg%tests(i))
            call simulate_effect(model, eff(i), test%hist, tg%t, self%prob%cfg%solver, res, err, &
                                 test%temperature, self%states)
            if (allocated(err)) then
               failed(it) = .true.
               return
            end if
            n = size(tg%t)
            ysim = simulated(test, res)
            r(k0(it) + 1:k0(it) + n) = test_residuals(self%prob%cfg%fit%objective, tg%y_ex, ysim, tg%w, &
                                                      tg%y_ex_max)
            if (allocated(self%test_scale)) r(k0(it) + 1:k0(it) + n) = self%test_scale(i)*r(k0(it) + 1:k0(it) + n)
            if (present(fitted)) fitted(k0(it) + 1:k0(it) + n) = ysim
            if (present(strain)) strain(k0(it) + 1:k0(it) + n) = res%strain
            if (present(eps_in)) eps_in(k0(it) + 1:k0(it) + n) = res%eps_in
         end associate
      end subroutine one
   end subroutine ep_residual_at

   !> A test's response with the effects eff, at the data's times t (s): the model the test
   !> sees (effect_model, at temperature, K, when > 0), the stress channel lagging by the
   !> shift, and an extensometer drift that a strain-controlled specimen follows less (the
   !> measured strain is then the specimen's plus the drift); with states, the extended
   !> model's p and R2 carried where eff leaves them at rest (see simulate_rosenbrock)
   subroutine simulate_effect(model, eff, hist0, t, solver, res, error, temperature, states)
      class(model_type), intent(in) :: model
      type(test_effects), intent(in) :: eff
      type(history_type), intent(in) :: hist0
      real(dp), intent(in) :: t(:)
      type(solver_options), intent(in) :: solver
      type(sim_result), intent(out) :: res
      type(error_type), allocatable, intent(out) :: error
      real(dp), intent(in), optional :: temperature
      logical, intent(in), optional :: states
      class(model_type), allocatable :: mt
      type(history_type) :: hist
      real(dp), allocatable :: tout(:)
      call effect_model(model, eff, mt, error, temperature)
      if (allocated(error)) return
      ! The stress channel lags by shift: the data at t saw the response at t - shift
      tout = min(max(t - eff%shift, hist0%t(1)), hist0%end_time())
      ! A strain-controlled specimen follows the command less the drift, a stress-controlled
      ! one the command read through the gain (both linear, so the corners stay the
      ! corners; the history is copied only then)
      if ((eff%drift /= 0.0_dp .and. hist0%control == control_strain) .or. &
          (eff%gain /= 0.0_dp .and. hist0%control == control_stress)) then
         hist = hist0
         if (hist%control == control_strain) call hist%add_ramp(-eff%drift)
         if (hist%control == control_stress) call hist%scale(1.0_dp/(1.0_dp + eff%gain))
         call simulate_on(hist)
      else
         call simulate_on(hist0)
      end if
      if (allocated(error)) return
      if (eff%drift /= 0.0_dp) res%strain = res%strain + eff%drift*(tout - hist0%t(1))
      if (eff%gain /= 0.0_dp) res%stress = (1.0_dp + eff%gain)*res%stress
   contains
      subroutine simulate_on(h)
         type(history_type), intent(in) :: h
         if (solver%integrator == 'cvode') then
            call simulate_cvode(mt, h, tout, solver, res, error, eff)
         else
            call simulate_rosenbrock(mt, h, tout, solver, res, error, eff, states)
         end if
      end subroutine simulate_on
   end subroutine simulate_effect

   !> Residuals at the points xs(:, j), in parallel; a failed point gets a large penalty. A
   !> test's rows are made from what its simulation sees (see test_inputs): where that is
   !> what it saw at the last point evaluated alone, or at an earlier point of the batch, its
   !> rows are copied from there (the same numbers), else the test is simulated. A
   !> difference column of one test's own parameter so simulates that test alone, from any
   !> base point; nevals counts points, nsims the tests simulated
   subroutine ep_residuals(self, xs, rs, fs, ok, error)
      class(effect_problem), intent(inout) :: self
      real(dp), intent(in) :: xs(:, :)
      real(dp), intent(out) :: rs(:, :)
      real(dp), intent(out) :: fs(:)
      logical, intent(out) :: ok(:)
      type(error_type), allocatable, intent(out) :: error
      real(dp), allocatable :: seen(:, :, :)
      integer, allocatable :: src(:, :), row0(:), rows(:), jobs(:, :)
      logical, allocatable :: tok(:, :)
      integer :: j, b, n, it, ntr, q
      logical :: last_ok
      n = size(xs, 2)
      ntr = size(self%tests)
      row0 = self%first_rows()
      rows = [(size(self%prob%targets(self%tests(it))%t), it=1, ntr)]
      seen = spread(self%test_inputs(xs(:, 1)), 3, n)
      do j = 2, n
         seen(:, :, j) = self%test_inputs(xs(:, j))
      end do
      last_ok = .false.
      if (allocated(self%seen_last)) last_ok = all(shape(self%seen_last) == shape(seen(:, :, 1)))
      ! src(it, j): where test it's rows of point j come from: -1 its simulation, 0 the last
      ! point, b > 0 column b of the batch
      allocate (src(ntr, n), tok(ntr, n))
      src = -1
      do j = 1, n
         do it = 1, ntr
            if (last_ok) then
               if (all(seen(:, it, j) == self%seen_last(:, it))) then
                  src(it, j) = 0
                  cycle
               end if
            end if
            do b = 1, j - 1
               if (all(seen(:, it, j) == seen(:, it, b))) then
                  src(it, j) = b
                  exit
               end if
            end do
         end do
      end do
      allocate (jobs(2, count(src == -1)))
      q = 0
      do j = 1, n
         do it = 1, ntr
            if (src(it, j) /= -1) cycle
            q = q + 1
            jobs(:, q) = [it, j]
         end do
      end do
      tok = .true.
      self%nsims = self%nsims + size(jobs, 2)
      ! Inside a team already (the starts of best_of_starts run as its tasks) the simulations
      ! are tasks too, which a thread whose own start waits or has ended takes up; otherwise a
      ! team of their own. Each test is simulated alone either way: the same numbers.
      if (omp_in_parallel()) then
         !$omp taskloop grainsize(1)
         do q = 1, size(jobs, 2)
            call simulate_job(q)
         end do
         !$omp end taskloop
      else
         !$omp parallel do schedule(dynamic)
         do q = 1, size(jobs, 2)
            call simulate_job(q)
         end do
         !$omp end parallel do
      end if
      ! the copies, in the order of the points (an earlier column's rows are final)
      do j = 1, n
         do it = 1, ntr
            associate (r => rs(row0(it) + 1:row0(it) + rows(it), j))
               if (src(it, j) == 0) then
                  r = self%r_last(row0(it) + 1:row0(it) + rows(it))
               else if (src(it, j) > 0) then
                  r = rs(row0(it) + 1:row0(it) + rows(it), src(it, j))
                  tok(it, j) = tok(it, src(it, j))
               end if
            end associate
         end do
         ok(j) = all(tok(:, j)) .and. all(abs(rs(:, j)) < huge(1.0_dp))
         fs(j) = merge(sum(rs(:, j)**2), failed_objective, ok(j))
      end do
      self%nevals = self%nevals + n
      if (n == 1 .and. ok(1)) then
         self%seen_last = seen(:, :, 1)
         self%r_last = rs(:, 1)
      end if

   contains

      !> Simulation q: test jobs(1, q) at point jobs(2, q), into its rows of rs
      subroutine simulate_job(q)
         integer, intent(in) :: q
         real(dp), allocatable :: r(:)
         associate (it => jobs(1, q), j => jobs(2, q))
            allocate (r(size(rs, 1)))
            r = 0.0_dp
            call self%residual_at(xs(:, j), r, tok(it, j), only=it)
            rs(row0(it) + 1:row0(it) + rows(it), j) = r(row0(it) + 1:row0(it) + rows(it))
         end associate
      end subroutine simulate_job
   end subroutine ep_residuals

   !> Each test's first row less one in the problem's residuals (its tests in order)
   pure function ep_first_rows(self) result(k0)
      class(effect_problem), intent(in) :: self
      integer :: k0(size(self%tests))
      integer :: it
      k0(1) = 0
      do it = 2, size(self%tests)
         k0(it) = k0(it - 1) + size(self%prob%targets(self%tests(it - 1))%t)
      end do
   end function ep_first_rows

   !> The effects each test of prob sees (prob's tests) with the parameters p (physical units)
   pure function ep_effects_at(self, p) result(eff)
      class(effect_problem), intent(in) :: self
      real(dp), intent(in) :: p(:)
      type(test_effects), allocatable :: eff(:)
      integer :: it, nt
      nt = size(self%prob%targets)
      if (self%k > 0) then
         eff = effects_of(self%k, p, nt, self%base)
         if (self%effect_test > 0) then
            do it = 1, nt
               if (it /= self%effect_test) eff(it) = self%base
            end do
         end if
      else
         allocate (eff(nt))
         eff = self%base
      end if
   end function ep_effects_at

   !> What makes each test's residuals at x besides its data, as reals (a column per test of
   !> the problem): the model's constants, the effects the test sees, the integrator's
   !> settings and the test's factor on its residuals. The problem's set-up enters through
   !> them (a start's p0, the constants held, a tighter tolerance), not through x alone.
   function ep_test_inputs(self, x) result(seen)
      class(effect_problem), intent(in) :: self
      real(dp), intent(in) :: x(:)
      real(dp), allocatable :: seen(:, :)
      class(model_type), allocatable :: model
      type(test_effects), allocatable :: eff(:)
      real(dp), allocatable :: p(:), c(:)
      integer :: it, i, ic
      call self%unpack(x, model, p)
      eff = self%effects_at(p)
      c = [(model%get_constant(ic), ic=1, model%n_constants())]
      associate (s => self%prob%cfg%solver)
         c = [c, s%rtol, s%atol_strain, s%max_step, real(s%max_steps, dp), &
              merge(1.0_dp, 0.0_dp, s%integrator == 'cvode')]
      end associate
      allocate (seen(size(c) + size(effect_reals(eff(1))) + 1, size(self%tests)))
      do it = 1, size(self%tests)
         i = self%tests(it)
         seen(:, it) = [c, effect_reals(eff(i)), 1.0_dp]
         if (allocated(self%test_scale)) seen(size(seen, 1), it) = self%test_scale(i)
      end do
   end function ep_test_inputs

   subroutine ep_eval(self, x, f, error)
      class(effect_problem), intent(inout) :: self
      real(dp), intent(in) :: x(:)
      real(dp), intent(out) :: f
      type(error_type), allocatable, intent(out) :: error
      real(dp), allocatable :: rs(:, :)
      real(dp) :: fs(1)
      logical :: ok(1)
      allocate (rs(self%nres(), 1))
      call self%residuals(reshape(x, [size(x), 1]), rs, fs, ok, error)
      f = fs(1)
   end subroutine ep_eval
end module usharp_effect_problem
