!> The fit problem: tests with data, the objective of the thesis (Eq. 7 per test summed by
!> Eq. 8, or Eq. 13) and the original's penalties
module usharp_objective
   use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
   use, intrinsic :: iso_fortran_env, only: int64
   use usharp_kinds, only: dp
   use usharp_math, only: log_dp, log10_dp, pow10_dp
   use usharp_error, only: error_type, fatal_error, prefix_error, stat_input
   use usharp_model, only: model_type, model_at
   use usharp_history, only: control_stress
   use usharp_units, only: stress_factor
   use usharp_simulation, only: sim_result
   use usharp_simulate, only: simulate_test, test_model
   use usharp_cvode_driver, only: simulate_cvode
   use usharp_config, only: run_config, test_config
   use usharp_experiment, only: experiment_type, load_experiment, interpolate, fits_strain, check_scale, &
                                compare_where_measured, check_programme
   use usharp_weighting, only: threshold_weights, relaxation_weights, rate_signal
   use usharp_external, only: run_external
   use usharp_filesys, only: join_path
   use usharp_strings, only: str
   use usharp_mpi, only: n_ranks, this_rank, block_of, share_blocks
   implicit none
   private

   public :: fit_problem, test_target, test_objective, test_residuals, setup_problem, message_len
   public :: simulated
   public :: eval_ok, eval_invalid, eval_failed, penalty_invalid, penalty_failed

   !> Length of the messages of a batch evaluation
   integer, parameter :: message_len = 1024
   !> Outcome of one evaluation
   integer, parameter :: eval_ok = 0, eval_invalid = 1, eval_failed = 2
   !> The original's penalties per test: invalid constants, failed simulation
   real(dp), parameter :: penalty_invalid = 1.0e10_dp, penalty_failed = 2.0e10_dp

   !> One test's target: experimental stress and weights at the simulation's output times
   type :: test_target
      real(dp), allocatable :: t(:)     !< s
      real(dp), allocatable :: y_ex(:)  !< model unit
      real(dp), allocatable :: w(:)
      !> largest |value| of the data within the compared times (and of the peaks compared)
      real(dp) :: y_ex_max = 0.0_dp
      type(experiment_type) :: exp
   end type test_target

   !> Everything needed to evaluate the objective for a vector of fitted parameters
   type :: fit_problem
      type(run_config) :: cfg
      type(test_target), allocatable :: targets(:)
      integer, allocatable :: idx(:)   !< indices of the fitted constants
   contains
      procedure :: model_of => problem_model_of
      procedure :: start_point => problem_start_point
      procedure :: evaluate => problem_evaluate
      procedure :: simulate_all => problem_simulate_all
      procedure :: response => problem_response
      procedure :: residuals => problem_residuals
      procedure :: nres => problem_nres
      procedure :: batch => problem_batch
      procedure :: merge => problem_merge
      procedure :: jacobian => problem_jacobian
   end type fit_problem

contains

   !> Load every test's data and precompute its target at the simulation's output times.
   !> experiments: the tests' data given directly (synthetic data), instead of their files
   subroutine setup_problem(cfg, prob, error, experiments)
      type(run_config), intent(in) :: cfg
      type(fit_problem), intent(out) :: prob
      type(error_type), allocatable, intent(out) :: error
      type(experiment_type), intent(in), optional :: experiments(:)
      integer :: i, k
      prob%cfg = cfg
      prob%idx = pack([(k, k=1, cfg%model%n_constants())], cfg%fit%fitted)
      if (size(prob%idx) == 0) then
         if (cfg%fit%present) then
            call fatal_error(error, cfg%path//': &fit: fitted names no constant to fit')
         else
            call fatal_error(error, cfg%path//': group &fit is missing (its fitted names the '// &
               'constants to fit)')
         end if
         return
      end if
      allocate (prob%targets(size(cfg%tests)))
      do i = 1, size(cfg%tests)
         if (cfg%tests(i)%ext%enabled .and. cfg%tests(i)%hist%control == control_stress) then
            ! The command reports stress only, which the load fixes: nothing to fit
            call fatal_error(error, 'backend = ''external'' reports stress only, and a '// &
                             'stress-controlled test has nothing to fit in it')
            exit
         end if
         if (present(experiments)) then
            prob%targets(i)%exp = experiments(i)
         else
            call load_experiment(cfg%tests(i), cfg%units, prob%targets(i)%exp, error)
            if (allocated(error)) exit
         end if
         ! Compared (and simulated) where the data hold a measurement
         call compare_where_measured(prob%cfg%tests(i), prob%targets(i)%exp)
         call set_target(prob%cfg%tests(i), cfg%units, prob%targets(i), error)
         if (allocated(error)) exit
         if (.not. present(experiments)) then
            associate (tg => prob%targets(i))
               ! (against every output time, not only those compared)
               call check_scale(cfg%tests(i), tg%exp, cfg%model%youngs, cfg%units, cfg%tests(i)%times(), error)
            end associate
            if (allocated(error)) exit
            call check_programme(cfg%tests(i), cfg%units, error)
            if (allocated(error)) exit
         end if
      end do
      if (allocated(error)) call prefix_error(error, cfg%path//": test '"//cfg%tests(i)%name//"': ")
   end subroutine setup_problem

   !> A test's target at its compared times (test%times()): its data interpolated there and
   !> the measured peak stresses at the turning points of a peaks target, with the weights of
   !> its weighting (on its data points). With both, the weights make the peaks' share of the
   !> test's objective peak_share: w = N share / n_peaks on the peaks and N (1 - share) /
   !> n_data times the weighting on the data points (N points in all)
   subroutine set_target(test, units, tg, error)
      type(test_config), intent(in) :: test
      character(len=*), intent(in) :: units
      type(test_target), intent(inout) :: tg
      type(error_type), allocatable, intent(out) :: error
      logical, allocatable :: on_data(:)
      real(dp), allocatable :: td(:), yd(:), wd(:)
      character(len=:), allocatable :: column
      integer :: n, nd
      real(dp) :: tol, within
      tg%t = test%times()
      n = size(tg%t)
      if (test%has_peaks()) then
         on_data = test%point_kind == 0
      else
         on_data = spread(.true., 1, n)
      end if
      nd = count(on_data)
      td = pack(tg%t, on_data)
      allocate (tg%y_ex(n), tg%w(n), yd(nd), wd(nd))
      tg%y_ex = 0.0_dp
      if (nd > 0) then
         call interpolate(tg%exp%t, tg%exp%y, td, yd, error)
         if (allocated(error)) then
            call prefix_error(error, test%data%file//': ')
            return
         end if
      end if
      tg%y_ex = unpack(yd, on_data, tg%y_ex)
      ! The peak of the test as simulated: rows outside its time (a creep curve to rupture
      ! cut at half its life) would set the scale of its residuals
      tg%y_ex_max = maxval(abs(tg%exp%y))
      if (n > 0) then
         tol = 1.0e-9_dp*max(1.0_dp, abs(tg%t(1)), abs(tg%t(n)))
         ! (where the rows within are all 0, the data's times are checked later: in ms?)
         within = maxval(abs(tg%exp%y), mask=tg%exp%t >= tg%t(1) - tol .and. tg%exp%t <= tg%t(n) + tol)
         if (within > 0.0_dp) tg%y_ex_max = within
      end if
      if (test%has_peaks()) then
         where (.not. on_data) tg%y_ex = test%peak_y*stress_factor(test%data%unit, units)
         tg%y_ex_max = max(tg%y_ex_max, maxval(abs(tg%y_ex), mask=.not. on_data))
      end if
      ! Eq. 7 and the weightings are relative to the measured peak: data that are 0 throughout
      ! would make every evaluation fail, and the fit end on an error about something else
      if (.not. tg%y_ex_max > 0.0_dp) then
         if (fits_strain(test)) then
            column = test%data%strain_col
         else
            column = test%data%stress_col
         end if
         call fatal_error(error, test%data%file//': column '''//column//''' is 0 at every row: '// &
            'the objective is relative to its peak (is it the right column?)', stat_input)
         return
      end if
      select case (test%weighting)
      case ('threshold')
         wd = threshold_weights(yd, test%sig)
      case ('relaxation')
         wd = relaxation_weights(td, rate_signal(td, yd, test%hist%t(test%hist%corners())), &
                                 hold_points(test%hist%t, test%hist%v, td))
      case ('column')
         if (nd > 0) call interpolate(tg%exp%t, tg%exp%weight, td, wd, error)
         if (allocated(error)) return
      case default
         wd = 1.0_dp
      end select
      tg%w = 1.0_dp
      tg%w = unpack(wd, on_data, tg%w)
      if (nd > 0 .and. nd < n) then
         tg%w = merge(tg%w*real(n, dp)*(1.0_dp - test%peak_share)/real(nd, dp), &
                      real(n, dp)*test%peak_share/real(n - nd, dp), on_data)
      end if
   end subroutine set_target

   !> Points that lie inside a hold (a segment of constant control value)
   pure function hold_points(tc, vc, t) result(hold)
      real(dp), intent(in) :: tc(:), vc(:), t(:)
      logical :: hold(size(t))
      integer :: i, k
      hold = .false.
      do k = 1, size(tc) - 1
         if (vc(k + 1) /= vc(k)) cycle
         do i = 1, size(t)
            if (t(i) > tc(k) .and. t(i) < tc(k + 1)) hold(i) = .true.
         end do
      end do
   end function hold_points

   !> One test's objective: Eq. 7 (percent of the peak, mean over points) or Eq. 13
   pure real(dp) function test_objective(kind, y_ex, y_sim, w, y_ex_max) result(s)
      character(len=*), intent(in) :: kind
      real(dp), intent(in) :: y_ex(:), y_sim(:), w(:), y_ex_max
      s = sum(test_residuals(kind, y_ex, y_sim, w, y_ex_max)**2)
   end function test_objective

   !> The starting point: the fitted constants of the input (log10 of them with log_search)
   pure function problem_start_point(self) result(x)
      class(fit_problem), intent(in) :: self
      real(dp) :: x(size(self%idx))
      integer :: j
      do j = 1, size(self%idx)
         x(j) = self%cfg%model%get_constant(self%idx(j))
         if (self%cfg%fit%log_search) x(j) = log10_dp(max(x(j), tiny(1.0_dp)))
      end do
   end function problem_start_point

   !> The model with the fitted constants set from x, checked and set up
   subroutine problem_model_of(self, x, model, error)
      class(fit_problem), intent(in) :: self
      real(dp), intent(in) :: x(:)
      class(model_type), allocatable, intent(out) :: model
      type(error_type), allocatable, intent(out) :: error
      integer :: j
      allocate (model, source=self%cfg%model)
      do j = 1, size(self%idx)
         if (self%cfg%fit%log_search) then
            call model%set_constant(self%idx(j), pow10_dp(x(j)))
         else
            call model%set_constant(self%idx(j), x(j))
         end if
      end do
      call model%setup(error)
   end subroutine problem_model_of

   !> Simulate every test with the model of x; error on the first failure. tag names the
   !> work folders of external tests ('best' when absent).
   subroutine problem_simulate_all(self, model, res, error, tag)
      class(fit_problem), intent(in) :: self
      class(model_type), intent(in) :: model
      type(sim_result), intent(out) :: res(:)
      type(error_type), allocatable, intent(out) :: error
      character(len=*), intent(in), optional :: tag
      integer :: i
      do i = 1, size(self%cfg%tests)
         if (present(tag)) then
            call self%response(i, model, tag, res(i), error)
         else
            call self%response(i, model, 'best', res(i), error)
         end if
         if (allocated(error)) return
      end do
   end subroutine problem_simulate_all

   !> Response of test i at its output times: the internal integrator, or the external
   !> command (its stress; strain from the history; inelastic strain as strain - stress/E;
   !> back and drag stress are not known there and set to 0). tag names the work folder.
   subroutine problem_response(self, i, model, tag, res, error)
      class(fit_problem), intent(in) :: self
      integer, intent(in) :: i
      class(model_type), intent(in) :: model
      character(len=*), intent(in) :: tag
      type(sim_result), intent(out) :: res
      type(error_type), allocatable, intent(out) :: error
      integer :: k
      class(model_type), allocatable :: mt
      associate (test => self%cfg%tests(i))
         if (.not. test%ext%enabled) then
            call simulate_test(model, self%cfg%solver, test, res, error)
            return
         end if
         call res%allocate(size(self%targets(i)%t))
         res%t = self%targets(i)%t
         ! (the constants file at the test's own temperature: its D0)
         call test_model(model, test, mt, error)
         if (.not. allocated(error)) &
            call run_external(test%ext, mt, self%cfg%units, test%hist, test%name, &
                              self%cfg%base_dir, self%cfg%out_dir, tag, res%t, &
                              res%stress, error)
         if (allocated(error)) then
            call prefix_error(error, "test '"//test%name//"': ")
            return
         end if
         do k = 1, size(res%t)
            res%strain(k) = test%hist%value_at(res%t(k))
         end do
         res%eps_in = res%strain - res%stress/model%youngs
         res%back = 0.0_dp
         res%drag = 0.0_dp
      end associate
   end subroutine problem_response

   !> The simulated response that a test's data are compared with: strain for a stress-
   !> controlled test, stress otherwise
   pure function simulated(test, res) result(y)
      type(test_config), intent(in) :: test
      type(sim_result), intent(in) :: res
      real(dp), allocatable :: y(:)
      if (fits_strain(test)) then
         y = res%strain
      else
         y = res%stress
      end if
   end function simulated

   !> Number of residuals: one per output point of every test
   pure integer function problem_nres(self) result(m)
      class(fit_problem), intent(in) :: self
      integer :: i
      m = 0
      do i = 1, size(self%targets)
         m = m + size(self%targets(i)%t)
      end do
   end function problem_nres

   !> Weighted residuals of one test whose squares sum to its objective: Eq. 7,
   !> sqrt(w/N)*100*(y_ex - y_sim)/max|y_ex|, or Eq. 13, sqrt(w)*(y_ex - y_sim)
   pure function test_residuals(kind, y_ex, y_sim, w, y_ex_max) result(r)
      character(len=*), intent(in) :: kind
      real(dp), intent(in) :: y_ex(:), y_sim(:), w(:), y_ex_max
      real(dp) :: r(size(y_ex))
      if (kind == 'eq13') then
         r = sqrt(w)*(y_ex - y_sim)
      else
         r = sqrt(w/real(size(y_ex), dp))*100.0_dp*(y_ex - y_sim)/y_ex_max
      end if
   end function test_residuals

   !> Objective at x: per-test values and their sum (Eq. 8). Invalid constants give the
   !> original's 1e10 per test, a failed simulation 2e10 per test; status and message say why.
   !> tag (the evaluation's number) names the work folders of external tests.
   subroutine problem_evaluate(self, x, total, per_test, status, message, tag)
      class(fit_problem), intent(in) :: self
      real(dp), intent(in) :: x(:)
      real(dp), intent(out) :: total
      real(dp), intent(out) :: per_test(:)
      integer, intent(out) :: status
      character(len=:), allocatable, intent(out) :: message
      character(len=*), intent(in), optional :: tag
      real(dp) :: r(self%nres())
      if (present(tag)) then
         call self%residuals(x, r, total, per_test, status, message, tag)
      else
         call self%residuals(x, r, total, per_test, status, message, 'eval')
      end if
   end subroutine problem_evaluate

   !> Residuals at x (test after test, see test_residuals), the per-test objectives and their
   !> sum; on a failure status says why and r is 0. With only, the tests i where only(i) is
   !> true alone (the others' residuals and objectives 0, and the sum not checked): a share of
   !> the tests that other ranks complete (see merge_shares).
   subroutine problem_residuals(self, x, r, total, per_test, status, message, tag, only, failed, &
                                seconds)
      class(fit_problem), intent(in) :: self
      real(dp), intent(in) :: x(:)
      real(dp), intent(out) :: r(:)
      real(dp), intent(out) :: total
      real(dp), intent(out) :: per_test(:)
      integer, intent(out) :: status
      character(len=:), allocatable, intent(out) :: message
      character(len=*), intent(in) :: tag
      logical, intent(in), optional :: only(:)
      !> the first test whose simulation failed (0: none, or the constants are invalid)
      integer, intent(out), optional :: failed
      !> wall time of each test's simulation (s), added to
      real(dp), intent(inout), optional :: seconds(:)
      class(model_type), allocatable :: model
      type(sim_result) :: res
      type(error_type), allocatable :: error
      integer :: i, k0, n
      integer(int64) :: c0, c1, rate
      status = eval_ok
      message = ''
      r = 0.0_dp
      per_test = 0.0_dp
      if (present(failed)) failed = 0
      call self%model_of(x, model, error)
      if (allocated(error)) then
         status = eval_invalid
         message = error%message
         per_test = penalty_invalid
         total = sum(per_test)
         return
      end if
      k0 = 0
      do i = 1, size(self%targets)
         n = size(self%targets(i)%t)
         if (present(only)) then
            if (.not. only(i)) then
               k0 = k0 + n
               cycle
            end if
         end if
         call system_clock(c0, rate)
         call self%response(i, model, tag, res, error)
         call system_clock(c1)
         if (present(seconds)) seconds(i) = seconds(i) + real(c1 - c0, dp)/real(rate, dp)
         if (allocated(error)) then
            status = eval_failed
            message = error%message
            if (present(failed)) failed = i
            per_test = penalty_failed
            total = sum(per_test)
            r = 0.0_dp
            return
         end if
         r(k0 + 1:k0 + n) = test_residuals(self%cfg%fit%objective, self%targets(i)%y_ex, &
                                           simulated(self%cfg%tests(i), res), &
                                           self%targets(i)%w, self%targets(i)%y_ex_max)
         per_test(i) = sum(r(k0 + 1:k0 + n)**2)
         k0 = k0 + n
      end do
      total = sum(per_test)
      if (present(only)) return
      call check_total(total, r, per_test, status, message)
   end subroutine problem_residuals

   !> A sum of the per-test objectives that is not finite is a failed evaluation
   pure subroutine check_total(total, r, per_test, status, message)
      real(dp), intent(inout) :: total, r(:), per_test(:)
      integer, intent(inout) :: status
      character(len=:), allocatable, intent(inout) :: message
      if (ieee_is_finite(total)) return
      status = eval_failed
      message = 'objective is not finite'
      per_test = penalty_failed
      total = sum(per_test)
      r = 0.0_dp
   end subroutine check_total

   !> One evaluation whose tests were simulated in shares (problem_residuals with only, a
   !> share a rank): the shares' residuals and objectives joined, as one rank simulating
   !> every test in order has them, bit for bit. The first failed test in order decides a
   !> failure (its status and message), as it ends that rank's evaluation there.
   subroutine problem_merge(self, owner, rs, per_tests, statuses, faileds, messages, r, total, &
                            per_test, status, message)
      class(fit_problem), intent(in) :: self
      !> the share that simulated each test (an index of the last dimension below)
      integer, intent(in) :: owner(:)
      !> each share's residuals, per-test objectives, status, first failed test, message
      real(dp), intent(in) :: rs(:, :), per_tests(:, :)
      integer, intent(in) :: statuses(:), faileds(:)
      character(len=*), intent(in) :: messages(:)
      real(dp), intent(out) :: r(:), total, per_test(:)
      integer, intent(out) :: status
      character(len=:), allocatable, intent(out) :: message
      integer :: i, k0, n, w, first
      r = 0.0_dp
      ! Invalid constants: every share found them so, alike
      if (any(statuses == eval_invalid)) then
         call penalise(findloc(statuses, eval_invalid, 1), penalty_invalid)
         return
      end if
      first = 0
      do w = 1, size(statuses)
         if (statuses(w) /= eval_failed .or. faileds(w) < 1) cycle
         if (first == 0) then
            first = w
         else if (faileds(w) < faileds(first)) then
            first = w
         end if
      end do
      if (first > 0) then
         call penalise(first, penalty_failed)
         return
      end if
      status = eval_ok
      message = ''
      k0 = 0
      do i = 1, size(self%targets)
         n = size(self%targets(i)%t)
         r(k0 + 1:k0 + n) = rs(k0 + 1:k0 + n, owner(i))
         per_test(i) = per_tests(i, owner(i))
         k0 = k0 + n
      end do
      total = sum(per_test)
      call check_total(total, r, per_test, status, message)
   contains
      !> The evaluation penalised as share w found it
      subroutine penalise(w, penalty)
         integer, intent(in) :: w
         real(dp), intent(in) :: penalty
         status = statuses(w)
         message = trim(messages(w))
         per_test = penalty
         total = sum(per_test)
      end subroutine penalise
   end subroutine problem_merge
   !> Jacobian of the residuals with respect to x from CVODES forward sensitivities (one
   !> simulation per test, tests in parallel); ok false where that is not available (the
   !> umat integrator, an external backend) or a simulation failed
   subroutine problem_jacobian(self, x, jac, ok)
      class(fit_problem), intent(in) :: self
      real(dp), intent(in) :: x(:)
      real(dp), intent(out) :: jac(:, :)
      logical, intent(out) :: ok
      class(model_type), allocatable :: model
      type(error_type), allocatable :: error
      integer :: i, j, n
      integer, allocatable :: k0(:)
      logical :: oks(size(self%targets))
      real(dp) :: dcdx(size(x))
      jac = 0.0_dp
      ! CVODES also serves the rodas4 fits: a Jacobian needs not match the integrator's error
      ok = self%cfg%solver%integrator /= 'umat' .and. .not. any(self%cfg%tests%ext%enabled)
      if (.not. ok) return
      call self%model_of(x, model, error)
      if (allocated(error)) then
         ok = .false.
         return
      end if
      do j = 1, size(x)
         dcdx(j) = 1.0_dp
         if (self%cfg%fit%log_search) dcdx(j) = model%get_constant(self%idx(j))*log_dp(10.0_dp)
      end do
      allocate (k0(size(self%targets)))
      k0(1) = 0
      do i = 2, size(self%targets)
         k0(i) = k0(i - 1) + size(self%targets(i - 1)%t)
      end do
      !$omp parallel do schedule(dynamic) private(n)
      do i = 1, size(self%targets)
         n = size(self%targets(i)%t)
         call one_test(i, jac(k0(i) + 1:k0(i) + n, :), oks(i))
      end do
      !$omp end parallel do
      ok = all(oks)
   contains
      subroutine one_test(i, jt, oki)
         integer, intent(in) :: i
         real(dp), intent(out) :: jt(:, :)
         logical, intent(out) :: oki
         type(sim_result) :: res
         type(error_type), allocatable :: err
         real(dp), allocatable :: deps(:, :), drdy(:), unit(:)
         integer :: jj
         class(model_type), allocatable :: mt
         associate (test => self%cfg%tests(i), tg => self%targets(i))
            if (test%temperature > 0.0_dp) then
               ! The test's own temperature
               call model_at(model, test%temperature, mt, err)
            else
               allocate (mt, source=model)
            end if
            if (.not. allocated(err)) call simulate_cvode(mt, test%hist, tg%t, self%cfg%solver, res, &
                                                          err, sens=self%idx, deps_in=deps)
            oki = .not. allocated(err)
            if (.not. oki) return
            ! d y_sim / d eps_in: -E under strain control (stress), 1 under stress control
            if (fits_strain(test)) then
               unit = spread(1.0_dp, 1, size(tg%t))
            else
               unit = spread(-model%youngs, 1, size(tg%t))
            end if
            ! d r / d y_sim: the residuals are linear in y_sim
            drdy = -test_residuals(self%cfg%fit%objective, spread(1.0_dp, 1, size(tg%t)), &
                                   spread(0.0_dp, 1, size(tg%t)), tg%w, tg%y_ex_max)
            do jj = 1, size(x)
               jt(:, jj) = drdy*unit*deps(:, jj)*dcdx(jj)
            end do
            oki = all(ieee_is_finite(jt))
         end associate
      end subroutine one_test
   end subroutine problem_jacobian

   !> Residuals at the points xs(:, j) (evaluation numbers k0 + j, after prefix, name the
   !> external work folders: a batch outside the fit's evaluations gives a prefix of its own so
   !> that no two runs share a folder), simulated in parallel with OpenMP; each point is
   !> independent of the others
   subroutine problem_batch(self, xs, k0, rs, fs, per_test, status, messages, prefix, spread, &
                            only, failed, seconds)
      class(fit_problem), intent(in) :: self
      real(dp), intent(in) :: xs(:, :)
      integer, intent(in) :: k0
      real(dp), intent(out) :: rs(:, :), fs(:), per_test(:, :)
      integer, intent(out) :: status(:)
      character(len=message_len), intent(out) :: messages(:)
      character(len=*), intent(in), optional :: prefix
      !> Ranks in lockstep (every rank calls this with the same points) each simulate their
      !> block of the points (block_of) and every rank receives every result: the same as
      !> one rank, bit for bit, since each point is simulated the same wherever it is
      logical, intent(in), optional :: spread
      !> A share of the tests alone (see problem_residuals), each point's first failed test,
      !> and the wall time of each test's simulations (s), added to
      logical, intent(in), optional :: only(:)
      integer, intent(out), optional :: failed(:)
      real(dp), intent(inout), optional :: seconds(:)
      character(len=:), allocatable :: tag0
      integer :: j, lo, hi
      logical :: split
      real(dp) :: sec(size(per_test, 1), size(xs, 2))
      integer :: fail(size(xs, 2))
      tag0 = ''
      if (present(prefix)) tag0 = prefix
      split = .false.
      if (present(spread)) split = spread .and. n_ranks() > 1
      lo = 1
      hi = size(xs, 2)
      if (split) call block_of(size(xs, 2), this_rank(), n_ranks(), lo, hi)
      sec = 0.0_dp
      fail = 0
      !$omp parallel do schedule(dynamic)
      do j = lo, hi
         call one_point(j)
      end do
      !$omp end parallel do
      if (split) then
         call share_blocks(rs)
         call share_blocks(fs)
         call share_blocks(per_test)
         call share_blocks(status)
         call share_blocks(messages)
      end if
      if (present(failed)) failed = fail
      if (present(seconds)) seconds = seconds + sum(sec, 2)
   contains
      subroutine one_point(j)
         integer, intent(in) :: j
         character(len=:), allocatable :: msg
         character(len=24) :: number
         ! The point's number by an internal write: gfortran 12 keeps the length of a
         ! function's deferred-length result (str's) in a static variable at each call, which
         ! the threads of this loop share
         write (number, '(i0)') k0 + j
         if (present(only)) then
            call self%residuals(xs(:, j), rs(:, j), fs(j), per_test(:, j), status(j), msg, &
                                tag0//trim(number), only, fail(j), sec(:, j))
         else
            call self%residuals(xs(:, j), rs(:, j), fs(j), per_test(:, j), status(j), msg, &
                                tag0//trim(number))
         end if
         messages(j) = msg
      end subroutine one_point
   end subroutine problem_batch
end module usharp_objective
