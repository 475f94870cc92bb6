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
   use usharp_objective, only: fit_problem, test_residuals, simulated
   use usharp_optimiser, only: least_squares_type
   use usharp_simulation, only: sim_result, solver_options
   use usharp_history, only: history_type, control_strain
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
      !> The last point evaluated on its own and its residuals: a point that differs from it
      !> only in one test's own parameters (a difference step of a per-test parameter)
      !> simulates that test alone and copies the others' rows
      real(dp), allocatable :: x_last(:), r_last(:)
   contains
      procedure :: residuals => ep_residuals
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
      integer :: it, nt, ntr
      ok = .false.
      if (.not. present(only)) r = 0.0_dp
      call self%unpack(x, model, p)
      call model%setup(error)
      if (allocated(error)) return
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
      ! each test's first row less one
      allocate (k0(size(self%tests)), failed(size(self%tests)))
      k0(1) = 0
      do it = 2, size(self%tests)
         k0(it) = k0(it - 1) + size(self%prob%targets(self%tests(it - 1))%t)
      end do
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
                                 test%temperature)
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
   !> measured strain is then the specimen's plus the drift)
   subroutine simulate_effect(model, eff, hist0, t, solver, res, error, temperature)
      class(model_type), intent(in) :: model
      type(test_effects), intent(in) :: eff
      type(history_type), intent(in) :: hist0
      real(dp), intent(in) :: t(:)
      type(solver_options), intent(in) :: solver
      type(sim_result), intent(out) :: res
      type(error_type), allocatable, intent(out) :: error
      real(dp), intent(in), optional :: temperature
      class(model_type), allocatable :: mt
      type(history_type) :: hist
      real(dp), allocatable :: tout(:)
      call effect_model(model, eff, mt, error, temperature)
      if (allocated(error)) return
      ! The stress channel lags by shift: the data at t saw the response at t - shift
      tout = min(max(t - eff%shift, hist0%t(1)), hist0%end_time())
      ! (linear in time, so the corners stay the corners)
      hist = hist0
      if (eff%drift /= 0.0_dp .and. hist%control == control_strain) call hist%add_ramp(-eff%drift)
      if (solver%integrator == 'cvode') then
         call simulate_cvode(mt, hist, tout, solver, res, error, eff)
      else
         call simulate_rosenbrock(mt, hist, tout, solver, res, error, eff)
      end if
      if (allocated(error)) return
      if (eff%drift /= 0.0_dp) res%strain = res%strain + eff%drift*(tout - hist%t(1))
   end subroutine simulate_effect

   !> Residuals at the points xs(:, j), in parallel; a failed point gets a large penalty. A
   !> point that differs from the last point evaluated alone, or from an earlier point of the
   !> batch, only in one test's own parameters simulates that test alone (the others' rows are
   !> the same numbers); nevals counts points
   subroutine ep_residuals(self, xs, rs, fs, ok, error)
      class(effect_problem), intent(inout) :: self
      real(dp), intent(in) :: xs(:, :)
      real(dp), intent(out) :: rs(:, :)
      real(dp), intent(out) :: fs(:)
      logical, intent(out) :: ok(:)
      type(error_type), allocatable, intent(out) :: error
      integer, allocatable :: owner(:), ref(:), only(:)
      integer :: j, b, n
      logical :: last_ok
      n = size(xs, 2)
      owner = test_of_x(self)
      ! ref(j): 0 the last point, b > 0 column b of the batch, -1 none (every test simulated)
      allocate (ref(n), only(n))
      ref = -1
      only = 0
      last_ok = .false.
      if (allocated(self%x_last)) last_ok = size(self%x_last) == size(xs, 1)
      do j = 1, n
         if (last_ok) then
            only(j) = single_test(xs(:, j), self%x_last, owner)
            if (only(j) > 0) ref(j) = 0
         end if
         do b = 1, j - 1
            if (ref(j) >= 0) exit
            if (ref(b) /= -1) cycle
            only(j) = single_test(xs(:, j), xs(:, b), owner)
            if (only(j) > 0) ref(j) = b
         end do
      end do
      ! Inside a team already (the starts of best_of_starts run as its tasks) the points are
      ! tasks too, which a thread whose own start waits or has ended takes up; otherwise a
      ! team of their own. Each point is simulated alone either way: the same numbers.
      if (omp_in_parallel()) then
         !$omp taskloop grainsize(1)
         do j = 1, n
            call whole(j)
         end do
         !$omp end taskloop
         !$omp taskloop grainsize(1)
         do j = 1, n
            call one_test(j)
         end do
         !$omp end taskloop
      else
         !$omp parallel do schedule(dynamic)
         do j = 1, n
            call whole(j)
         end do
         !$omp end parallel do
         !$omp parallel do schedule(dynamic)
         do j = 1, n
            call one_test(j)
         end do
         !$omp end parallel do
      end if
      do j = 1, n
         fs(j) = merge(sum(rs(:, j)**2), failed_objective, ok(j))
      end do
      self%nevals = self%nevals + n
      if (n == 1 .and. ok(1)) then
         self%x_last = xs(:, 1)
         self%r_last = rs(:, 1)
      end if

   contains

      !> Point j with every test simulated (unless it is one test's own)
      subroutine whole(j)
         integer, intent(in) :: j
         if (ref(j) == -1) call self%residual_at(xs(:, j), rs(:, j), ok(j))
      end subroutine whole

      !> Point j with its one test simulated, the other rows those of its reference
      subroutine one_test(j)
         integer, intent(in) :: j
         if (ref(j) == -1) return
         if (ref(j) == 0) then
            rs(:, j) = self%r_last
         else
            rs(:, j) = rs(:, ref(j))
         end if
         call self%residual_at(xs(:, j), rs(:, j), ok(j), only=only(j))
         ok(j) = ok(j) .and. all(abs(rs(:, j)) < huge(1.0_dp))
      end subroutine one_test
   end subroutine ep_residuals

   !> For each component of x: the index (into the problem's tests) of the one test whose
   !> residuals alone it changes (a per-test parameter of that test), 0 when it changes all
   pure function test_of_x(self) result(owner)
      class(effect_problem), intent(in) :: self
      integer, allocatable :: owner(:)
      type(effect_info) :: cat(n_effects)
      integer :: nc, j, jx, nt, it
      nc = 0
      if (self%free_constants) nc = size(self%prob%idx)
      allocate (owner(nc + count(self%pfree)))
      owner = 0
      if (self%k == 0) return
      nt = size(self%prob%targets)
      if (self%effect_test > 0) then
         ! every effect parameter is that test's own
         do it = 1, size(self%tests)
            if (self%tests(it) == self%effect_test) owner(nc + 1:) = it
         end do
         return
      end if
      cat = effect_catalogue(1.0_dp)
      if (cat(self%k)%sharing /= param_per_test) return
      jx = nc
      do j = 1, size(self%p0)
         if (.not. self%pfree(j)) cycle
         jx = jx + 1
         do it = 1, size(self%tests)
            if (self%tests(it) == mod(j - 1, nt) + 1) owner(jx) = it
         end do
      end do
   end function test_of_x

   !> The one test (owner's index) in whose own parameters alone xa differs from xb; 0 when
   !> they are equal, or differ elsewhere or in several tests' parameters
   pure integer function single_test(xa, xb, owner) result(it)
      real(dp), intent(in) :: xa(:), xb(:)
      integer, intent(in) :: owner(:)
      integer :: j
      it = 0
      do j = 1, size(xa)
         if (xa(j) == xb(j)) cycle
         if (owner(j) == 0 .or. (it > 0 .and. owner(j) /= it)) then
            it = 0
            return
         end if
         it = owner(j)
      end do
   end function single_test

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
