!> A fit: the objective of a fit problem wrapped with the logs, the journal replay for
!> --resume, the failure count, and a progress report to a caller-supplied procedure
!> (the library itself never prints)
module usharp_fit
   use, intrinsic :: iso_fortran_env, only: int64
   use usharp_kinds, only: dp
   use usharp_math, only: log10_dp, pow10_dp
   use usharp_error, only: error_type, fatal_error, stat_failure, stat_input, stat_usage
   use usharp_strings, only: str, real_str
   use usharp_objective, only: fit_problem, eval_ok, eval_invalid, message_len
   use usharp_optimiser, only: least_squares_type, optimum_type
   use usharp_hooke_jeeves, only: hooke_jeeves
   use usharp_levenberg, only: levenberg_marquardt
   use usharp_nelder_mead, only: nelder_mead
   use usharp_annealing, only: anneal
   use usharp_sampling, only: latin_hypercube
   use usharp_rng, only: rng_type
   use usharp_fit_log, only: fit_log, journal_record, cached_jacobian, read_journal, read_cache, &
                             journal_name, cache_name, start_done
   use usharp_journal, only: fingerprint_mismatch, fingerprint_damaged
   use usharp_filesys, only: join_path, file_exists, file_hash, hash_hex, hash_text, read_line
   use usharp_signal, only: catch_stop_signals, release_stop_signals, stop_signal
   use usharp_version, only: usharp_version_string, build_id
   use usharp_config, only: run_config
   use usharp_mpi, only: n_ranks, this_rank, is_root, share, parallel_sync, tasks_per_share, &
                         task_deal, ranks_that_ran, any_rank, transfer_set, post_send, post_receive, &
                         header_waiting, receive_header, block_of, send_packet, receive_packet, &
                         tag_help, tag_help_result, counts_of_ranks
   implicit none
   private

   public :: fit_objective, run_fit, fit_outcome, progress_interface, fit_fingerprint

   !> Internal: a replay_only objective ran out of records; a start not run (after a stop)
   integer, parameter :: stat_exhausted = -1, stat_not_run = -2

   !> The evaluations of one start of a multi-start fit as a rank made them, and how it ended
   type :: start_log
      type(journal_record), allocatable :: recs(:)
      type(cached_jacobian), allocatable :: jacs(:)
      integer :: stat = 0        !< the stat of the error that ended it (0: none)
      integer :: nsimulated = 0
      !> An ended start that rank 0 logs from its records and optimum alone (see close_log)
      logical :: closed = .false.
      type(start_done) :: done
      !> On its way between its rank and rank 0: the packed fields and the transfers
      integer, allocatable :: ints(:)
      real(dp), allocatable :: reals(:)
      character(len=:), allocatable :: text
      type(transfer_set) :: moving
   end type start_log

   !> MPI tags of a start's evaluations sent to rank 0: the header (sizes), then the data
   integer, parameter :: tag_head = 71, tag_data = 72
   !> A start's header: s, records, Jacobians, stat, simulated, closed (1) and its optimum's
   !> evaluations, iterations and reason's length; then three per record
   integer, parameter :: nhead = 9


   abstract interface
      !> Called after every evaluation: evaluations so far, best objective, elapsed s
      subroutine progress_interface(nevals, best, seconds)
         import :: dp
         integer, intent(in) :: nevals
         real(dp), intent(in) :: best, seconds
      end subroutine progress_interface
   end interface

   !> The objective an optimiser sees during a fit
   type, extends(least_squares_type) :: fit_objective
      type(fit_problem) :: prob
      type(fit_log) :: log
      type(journal_record), allocatable :: replay(:)
      type(cached_jacobian), allocatable :: replay_jac(:)
      !> The starts the journal closes: replayed from its records alone (see replay_start)
      type(start_done), allocatable :: replay_done(:)
      integer :: nevals = 0
      integer :: nsens = 0              !< sensitivity Jacobians (one simulation each)
      integer :: nsimulated = 0         !< evaluations simulated (not replayed) in this run
      !> Evaluations taken from the journal in this run (those whose residual vectors a
      !> least-squares search needs only where fit.cache holds them)
      integer :: nreplayed = 0
      integer :: nfail_row = 0          !< failures in a row
      integer :: nfail_total = 0
      integer :: ninvalid_total = 0
      real(dp) :: best = huge(1.0_dp)
      real(dp) :: first = huge(1.0_dp)
      real(dp), allocatable :: best_per_test(:)
      real(dp), allocatable :: best_x(:)
      procedure(progress_interface), pointer, nopass :: progress => null()
      integer(int64) :: clock0 = 0
      integer :: nresumed = 0           !< leading records of replay that come from a journal
      !> Keep the evaluations in kept (another rank logs them) instead of logging them
      logical :: capture = .false.
      !> Stop with stat_exhausted where a simulation would be needed (replay what is there)
      logical :: replay_only = .false.
      character(len=:), allocatable :: tag  !< before the evaluation's number in external work folders
      type(journal_record), allocatable :: kept(:)
      type(cached_jacobian), allocatable :: kept_jac(:)
      integer :: nkept = 0
      integer, allocatable :: start_eval(:), start_sens(:)  !< first evaluation, Jacobian of each start
      integer :: start_now = 0  !< the start being searched
      !> The last start the search ended, as its journal line closes it (see replay_start)
      type(start_done) :: closed
      character(len=:), allocatable :: fingerprint  !< of the inputs, for the logs' first line
      character(len=:), allocatable :: journal  !< the journal's path, for messages
      !> Residual vectors or Jacobians were replayed from fit.cache (beside the journal)
      logical :: cache_used = .false.
      !> The deal of the run's starts over the ranks: ranks out of starts help with this
      !> search's batches (see shared_batch)
      type(task_deal), pointer :: deal => null()
      integer :: nhelped = 0  !< points this rank simulated for another rank's search
      integer :: nshared = 0  !< points of whose tests this rank simulated a share (shared_tests)
      !> Points sent ahead to helpers (see fit_prefetch) whose results are not taken yet,
      !> and the helpers that have them
      real(dp), allocatable :: ahead(:, :)
      integer, allocatable :: ahead_helpers(:)
      !> Each test's wall time per simulation as last measured (s), to share a batch's tests
      !> out evenly (see shared_tests); before a measurement, its number of compared points
      real(dp), allocatable :: test_cost(:)
   contains
      procedure :: eval => fit_eval
      procedure :: residuals => fit_residuals
      procedure :: jacobian => fit_jacobian
      procedure :: prefetch => fit_prefetch
      procedure :: nres => fit_nres
      procedure :: constants_of => fit_constants_of
      procedure :: record => fit_record
   end type fit_objective

   !> What a finished fit reports
   type :: fit_outcome
      type(optimum_type) :: opt
      real(dp) :: f_start = 0.0_dp
      real(dp), allocatable :: per_test(:)
      real(dp), allocatable :: constants(:)  !< fitted constants, physical units
      integer :: nfail = 0, ninvalid = 0, nreplayed = 0
      integer :: nsimulated = 0  !< evaluations and sensitivity Jacobians simulated in this run
      integer :: nstarts = 1  !< local searches run (multi-start)
      !> On each MPI rank, the points it simulated for another rank's search (see shared_batch),
      !> and those of whose tests it simulated a share (see shared_tests)
      integer, allocatable :: helped(:), shared(:)
      real(dp) :: seconds = 0.0_dp
   end type fit_outcome

contains

   !> Fitted constants in physical units for a search point x
   pure function fit_constants_of(self, x) result(c)
      class(fit_objective), intent(in) :: self
      real(dp), intent(in) :: x(:)
      real(dp) :: c(size(x))
      c = x
      if (self%prob%cfg%fit%log_search) c = pow10_dp(x)
   end function fit_constants_of

   pure integer function fit_nres(self) result(m)
      class(fit_objective), intent(in) :: self
      m = self%prob%nres()
   end function fit_nres

   !> One evaluation for a direct search: replayed from the journal when resuming
   subroutine fit_eval(self, x, f, error)
      class(fit_objective), intent(inout) :: self
      real(dp), intent(in) :: x(:)
      real(dp), intent(out) :: f
      type(error_type), allocatable, intent(out) :: error
      real(dp) :: per_test(size(self%prob%targets))
      integer :: status, k
      character(len=:), allocatable :: message
      k = self%nevals + 1
      if (k <= size(self%replay)) then
         call check_replay(self, k, x, error)
         if (allocated(error)) return
         f = self%replay(k)%f
         per_test = self%replay(k)%per_test
         status = self%replay(k)%status
         message = replay_message(self, k)
         self%nreplayed = self%nreplayed + 1
      else
         call may_simulate(self, error)
         if (allocated(error)) return
         call self%prob%evaluate(x, f, per_test, status, message, tag_of(self)//str(k))
         self%nsimulated = self%nsimulated + 1
         ! An evaluation a stop signal may have cut short is not logged
         call check_stop(self, error)
         if (allocated(error)) return
      end if
      call self%record(x, f, per_test, status, message, error)
   end subroutine fit_eval

   !> The sensitivity Jacobian when &fit jacobian = 'sensitivity' and the tests allow it
   !> (not logged: it is not an evaluation of the objective)
   subroutine fit_jacobian(self, x, jac, done, error)
      class(fit_objective), intent(inout) :: self
      real(dp), intent(in) :: x(:)
      real(dp), intent(out) :: jac(:, :)
      logical, intent(out) :: done
      type(error_type), allocatable, intent(out) :: error
      integer :: i
      done = .false.
      if (self%prob%cfg%fit%jacobian /= 'sensitivity') return
      i = self%nsens + 1
      if (i <= size(self%replay_jac)) then
         if (.not. allocated(self%replay_jac(i)%x)) then
            ! Not kept (a finished start's): simulated again
         else if (all(self%replay_jac(i)%x == x)) then
            jac = self%replay_jac(i)%jac
            done = .true.
            self%cache_used = .true.
         end if
      end if
      if (.not. done) then
         call may_simulate(self, error)
         if (allocated(error)) return
         call self%prob%jacobian(x, jac, done)
         self%nsimulated = self%nsimulated + 1
      end if
      if (.not. done) return
      self%nsens = i
      if (self%capture) then
         self%kept_jac = [self%kept_jac, cached_jacobian(x, jac)]
      else
         call self%log%record_jacobian(i, x, jac, error)
      end if
   end subroutine fit_jacobian

   !> Residuals at several points, simulated in parallel (OpenMP) and then logged in order,
   !> so the logs and the result do not depend on the number of threads
   subroutine fit_residuals(self, xs, rs, fs, ok, error)
      class(fit_objective), intent(inout) :: self
      real(dp), intent(in) :: xs(:, :)
      real(dp), intent(out) :: rs(:, :)
      real(dp), intent(out) :: fs(:)
      logical, intent(out) :: ok(:)
      type(error_type), allocatable, intent(out) :: error
      real(dp) :: per_test(size(self%prob%targets), size(xs, 2))
      integer :: status(size(xs, 2)), j, k0, nr
      character(len=message_len) :: messages(size(xs, 2))
      k0 = self%nevals
      ! The journal's leading points whose residuals fit.cache kept are replayed; the rest
      ! (a resumed run's first new points onwards) are simulated as one batch
      nr = 0
      do j = 1, size(xs, 2)
         if (k0 + j > size(self%replay)) exit
         call check_replay(self, k0 + j, xs(:, j), error)
         if (allocated(error)) return
         if (.not. allocated(self%replay(k0 + j)%r)) exit
         nr = j
         rs(:, j) = self%replay(k0 + j)%r
         fs(j) = self%replay(k0 + j)%f
         per_test(:, j) = self%replay(k0 + j)%per_test
         status(j) = self%replay(k0 + j)%status
         messages(j) = replay_message(self, k0 + j)
      end do
      self%nreplayed = self%nreplayed + nr
      if (nr > 0) self%cache_used = .true.
      if (nr < size(xs, 2)) then
         call may_simulate(self, error)
         if (allocated(error)) return
         call shared_batch(self, xs(:, nr + 1:), k0 + nr, rs(:, nr + 1:), fs(nr + 1:), &
                           per_test(:, nr + 1:), status(nr + 1:), messages(nr + 1:))
         self%nsimulated = self%nsimulated + size(xs, 2) - nr
         call check_stop(self, error)
         if (allocated(error)) return
      end if
      do j = 1, size(xs, 2)
         call self%record(xs(:, j), fs(j), per_test(:, j), status(j), trim(messages(j)), error, &
                          rs(:, j))
         if (allocated(error)) return
         ok(j) = status(j) == eval_ok
      end do
   end subroutine fit_residuals

   !> The points xs (evaluations k0 + j) simulated as one batch: by this rank alone, or, in a
   !> multi-start run whose other ranks are out of starts, in blocks with the helpers this
   !> rank can claim (see task_deal), each block simulated where it was sent; the helpers'
   !> blocks come first, this rank's is the last (the smallest). Blocks sent ahead for these
   !> very points (fit_prefetch) are taken as they are. A point is simulated the same
   !> wherever it runs, so the results are those of one rank, bit for bit.
   subroutine shared_batch(self, xs, k0, rs, fs, per_test, status, messages)
      class(fit_objective), intent(inout) :: self
      real(dp), intent(in) :: xs(:, :)
      integer, intent(in) :: k0
      real(dp), intent(out) :: rs(:, :), fs(:), per_test(:, :)
      integer, intent(out) :: status(:)
      character(len=message_len), intent(out) :: messages(:)
      integer, allocatable :: helpers(:)
      integer :: n, nw, lo, hi
      logical :: sent
      n = size(xs, 2)
      sent = .false.
      if (allocated(self%ahead)) then
         sent = all(shape(self%ahead) == shape(xs))
         if (sent) sent = all(self%ahead == xs)
         ! Blocks sent ahead for other points hold their helpers until taken; a single point
         ! (the next trial) is simulated here meanwhile
         if (.not. sent .and. n > 1) call drop_ahead(self)
      end if
      if (sent) then
         helpers = self%ahead_helpers
      else if (allocated(self%ahead)) then
         allocate (helpers(0))
      else
         ! Shares of the tests, where they spread the batch more evenly than blocks of points
         ! (a single trial point, or a difference Jacobian of few columns)
         ! (a single point asks for helpers only once every start is dealt: ranks out of
         ! starts are rare before, and each claim is a round trip to rank 0)
         if (.not. shares_possible(self)) then
            helpers = claim_helpers(self, n)
         else if (n > 1 .or. deal_done(self)) then
            helpers = claim_helpers(self, max(n, size(self%prob%targets)))
         else
            helpers = claim_helpers(self, 1)
         end if
         if (shares_win(self, n, size(helpers))) then
            call shared_tests(self, xs, k0, helpers, rs, fs, per_test, status, messages)
            return
         end if
         helpers = helpers(:min(size(helpers), n - 1))
         call send_blocks(self, xs, k0, helpers)
      end if
      nw = 1 + size(helpers)
      call block_of(n, nw - 1, nw, lo, hi)
      call self%prob%batch(xs(:, lo:hi), k0 + lo - 1, rs(:, lo:hi), fs(lo:hi), per_test(:, lo:hi), &
                           status(lo:hi), messages(lo:hi), tag_of(self))
      call receive_blocks(helpers, rs, fs, per_test, status, messages)
      if (sent) deallocate (self%ahead, self%ahead_helpers)
   end subroutine shared_batch

   !> Send the difference Jacobian's points at a trial point ahead to the helpers this rank
   !> can claim, while it simulates the trial itself (see least_squares_type's prefetch);
   !> taken by shared_batch if they are asked for, dropped otherwise. Not with an external
   !> backend, whose work folders are named by evaluation.
   subroutine fit_prefetch(self, xs)
      class(fit_objective), intent(inout) :: self
      real(dp), intent(in) :: xs(:, :)
      integer, allocatable :: helpers(:)
      if (.not. associated(self%deal) .or. allocated(self%ahead)) return
      if (any(self%prob%cfg%tests%ext%enabled)) return
      ! With more than one test the helpers take shares of the trial's tests instead
      if (size(self%prob%targets) > 1) return
      helpers = claim_helpers(self, size(xs, 2))
      if (size(helpers) == 0) return
      call send_blocks(self, xs, self%nevals + 1, helpers)
      self%ahead = xs
      self%ahead_helpers = helpers
   end subroutine fit_prefetch

   !> Take and drop the results of the blocks sent ahead (before the helpers do other work
   !> for this rank, or are freed)
   subroutine drop_ahead(self)
      class(fit_objective), intent(inout) :: self
      real(dp), allocatable :: rs(:, :), fs(:), per_test(:, :)
      integer, allocatable :: status(:)
      character(len=message_len), allocatable :: messages(:)
      integer :: n
      if (.not. allocated(self%ahead)) return
      n = size(self%ahead, 2)
      allocate (rs(self%prob%nres(), n), fs(n), per_test(size(self%prob%targets), n), status(n), &
                messages(n))
      call receive_blocks(self%ahead_helpers, rs, fs, per_test, status, messages)
      deallocate (self%ahead, self%ahead_helpers)
   end subroutine drop_ahead

   !> The helpers to share a batch of n points (or tests) with: those claimed now or before,
   !> at most n - 1 (a block each beside this rank's own)
   function claim_helpers(self, n) result(helpers)
      class(fit_objective), intent(inout) :: self
      integer, intent(in) :: n
      integer, allocatable :: helpers(:)
      allocate (helpers(0))
      if (.not. associated(self%deal) .or. n < 2) return
      call self%deal%claim(n - 1)
      helpers = self%deal%helper_ranks()
      helpers = helpers(:min(size(helpers), n - 1))
   end function claim_helpers

   !> Whether this search's rank knows every start to have been dealt (see task_deal)
   logical function deal_done(self) result(yes)
      class(fit_objective), intent(in) :: self
      yes = .false.
      if (associated(self%deal)) yes = self%deal%all_dealt()
   end function deal_done

   !> Whether shares of the tests spread a batch of n points over this rank and nh helpers
   !> better than blocks of points do: the points' speed-up n/ceil(n/w) against the tests'
   !> (their estimated time over the largest share's, see test_shares)
   logical function shares_win(self, n, nh) result(yes)
      class(fit_objective), intent(inout) :: self
      integer, intent(in) :: n, nh
      integer :: w
      real(dp) :: load(min(1 + nh, size(self%prob%targets)))
      integer :: owner(size(self%prob%targets))
      yes = .false.
      if (nh == 0 .or. .not. shares_possible(self)) return
      call ensure_costs(self)
      w = min(1 + nh, size(self%prob%targets))
      call test_shares(self%test_cost, w, owner, load)
      yes = sum(load)/maxval(load) > real(n, dp)/real((n + nh)/(1 + nh), dp)
   end function shares_win

   !> Whether a batch may be shared by tests: more than one, and no external backend (a
   !> share would run the FE jobs of tests that one rank skips after an earlier test failed,
   !> and keep their failed work folders unnamed)
   pure logical function shares_possible(self) result(yes)
      class(fit_objective), intent(in) :: self
      yes = size(self%prob%targets) > 1 .and. .not. any(self%prob%cfg%tests%ext%enabled)
   end function shares_possible

   !> Each test's cost before any is measured: its number of compared points
   subroutine ensure_costs(self)
      class(fit_objective), intent(inout) :: self
      integer :: i
      if (allocated(self%test_cost)) return
      allocate (self%test_cost(size(self%prob%targets)))
      do i = 1, size(self%prob%targets)
         self%test_cost(i) = real(size(self%prob%targets(i)%t), dp)
      end do
   end subroutine ensure_costs

   !> The tests dealt into w shares of about equal cost: the costliest first, each to the
   !> share least loaded so far (owner(i): test i's share; load: each share's cost)
   pure subroutine test_shares(cost, w, owner, load)
      real(dp), intent(in) :: cost(:)
      integer, intent(in) :: w
      integer, intent(out) :: owner(:)
      real(dp), intent(out) :: load(:)
      logical :: dealt(size(cost))
      integer :: k, i
      load = 0.0_dp
      dealt = .false.
      do k = 1, size(cost)
         i = maxloc(cost, 1, mask=.not. dealt)
         dealt(i) = .true.
         owner(i) = minloc(load(:w), 1)
         load(owner(i)) = load(owner(i)) + cost(i)
      end do
   end subroutine test_shares

   !> The points xs (evaluations k0 + j) simulated in shares of the tests: each helper its
   !> share of every point's tests, this rank the last share; the shares joined as one rank
   !> simulating every test has them (see fit_problem's merge), bit for bit
   subroutine shared_tests(self, xs, k0, helpers, rs, fs, per_test, status, messages)
      class(fit_objective), intent(inout) :: self
      real(dp), intent(in) :: xs(:, :)
      integer, intent(in) :: k0, helpers(:)
      real(dp), intent(out) :: rs(:, :), fs(:), per_test(:, :)
      integer, intent(out) :: status(:)
      character(len=message_len), intent(out) :: messages(:)
      integer :: nt, n, m, w, ws, j, from
      integer, allocatable :: owner(:), ints(:), stat_w(:, :), fail_w(:, :)
      real(dp), allocatable :: load(:), r_w(:, :, :), pt_w(:, :, :), sec(:), reals(:)
      character(len=message_len), allocatable :: msg_w(:, :)
      character(len=:), allocatable :: text, message
      nt = size(self%prob%targets)
      n = size(xs, 2)
      m = size(rs, 1)
      ws = min(1 + size(helpers), nt)
      allocate (owner(nt), load(ws), r_w(m, n, ws), pt_w(nt, n, ws), stat_w(n, ws), fail_w(n, ws), &
                msg_w(n, ws), sec(nt))
      call test_shares(self%test_cost, ws, owner, load)
      do w = 1, ws - 1
         call send_packet(helpers(w), tag_help, [2, k0, n, merge(1, 0, owner == w)], &
                          reshape(xs, [size(xs)]), tag_of(self))
      end do
      sec = 0.0_dp
      call self%prob%batch(xs, k0, r_w(:, :, ws), fs, pt_w(:, :, ws), stat_w(:, ws), msg_w(:, ws), &
                           tag_of(self), only=owner == ws, failed=fail_w(:, ws), seconds=sec)
      do w = 1, ws - 1
         from = helpers(w)
         call receive_packet(from, tag_help_result, ints, reals, text)
         stat_w(:, w) = ints(1:n)
         fail_w(:, w) = ints(n + 1:2*n)
         r_w(:, :, w) = reshape(reals(1:m*n), [m, n])
         pt_w(:, :, w) = reshape(reals(m*n + 1:(m + nt)*n), [nt, n])
         where (owner == w) sec = reals((m + nt)*n + 1:)
         do j = 1, n
            msg_w(j, w) = text((j - 1)*message_len + 1:j*message_len)
         end do
      end do
      do j = 1, n
         call self%prob%merge(owner, r_w(:, j, :), pt_w(:, j, :), stat_w(j, :), fail_w(j, :), &
                              msg_w(j, :), rs(:, j), fs(j), per_test(:, j), status(j), message)
         messages(j) = message
      end do
      ! The next batch shared by the tests' times now (a test cut short by an earlier
      ! failure in its share keeps its estimate)
      where (sec > 0.0_dp) self%test_cost = sec/real(n, dp)
   end subroutine shared_tests

   !> Send helper w its block w of the n = size(xs, 2) points (of 1 + size(helpers) blocks)
   subroutine send_blocks(self, xs, k0, helpers)
      class(fit_objective), intent(in) :: self
      real(dp), intent(in) :: xs(:, :)
      integer, intent(in) :: k0, helpers(:)
      integer :: w, lo, hi
      do w = 1, size(helpers)
         call block_of(size(xs, 2), w - 1, 1 + size(helpers), lo, hi)
         call send_packet(helpers(w), tag_help, [1, k0 + lo - 1, hi - lo + 1], &
                          reshape(xs(:, lo:hi), [size(xs, 1)*(hi - lo + 1)]), tag_of(self))
      end do
   end subroutine send_blocks

   !> Receive each helper's block of results (see send_blocks) into its columns
   subroutine receive_blocks(helpers, rs, fs, per_test, status, messages)
      integer, intent(in) :: helpers(:)
      real(dp), intent(inout) :: rs(:, :), fs(:), per_test(:, :)
      integer, intent(inout) :: status(:)
      character(len=message_len), intent(inout) :: messages(:)
      integer, allocatable :: ints(:)
      real(dp), allocatable :: reals(:)
      character(len=:), allocatable :: text
      integer :: w, lo, hi, b, m, nt, j, from
      m = size(rs, 1)
      nt = size(per_test, 1)
      do w = 1, size(helpers)
         call block_of(size(fs), w - 1, 1 + size(helpers), lo, hi)
         b = hi - lo + 1
         from = helpers(w)
         call receive_packet(from, tag_help_result, ints, reals, text)
         status(lo:hi) = ints
         rs(:, lo:hi) = reshape(reals(1:m*b), [m, b])
         fs(lo:hi) = reals(m*b + 1:(m + 1)*b)
         per_test(:, lo:hi) = reshape(reals((m + 1)*b + 1:), [nt, b])
         do j = lo, hi
            messages(j) = text((j - lo)*message_len + 1:(j - lo + 1)*message_len)
         end do
      end do
   end subroutine receive_blocks

   !> The end of this rank's search: results sent ahead dropped, the helpers freed
   subroutine end_helped(self)
      class(fit_objective), intent(inout) :: self
      if (.not. associated(self%deal)) return
      call drop_ahead(self)
      call self%deal%release()
      self%deal => null()
   end subroutine end_helped

   !> A rank out of starts: simulate the blocks of points the ranks still at work send it
   !> (see shared_batch) until every rank is out of starts
   subroutine help_others(prob, deal, nhelped, nshared)
      type(fit_problem), intent(in) :: prob
      type(task_deal), intent(inout) :: deal
      !> points simulated whole, and points of which a share of the tests was simulated, added to
      integer, intent(inout) :: nhelped, nshared
      integer, allocatable :: ints(:)
      real(dp), allocatable :: reals(:), rs(:, :), fs(:), per_test(:, :)
      character(len=:), allocatable :: tag, text
      character(len=message_len), allocatable :: messages(:)
      integer, allocatable :: status(:), failed(:)
      real(dp), allocatable :: seconds(:)
      integer :: owner, n, nx, j, nt
      if (.not. deal%offer()) return
      nx = size(prob%idx)
      do while (deal%await(owner, ints, reals, tag))
         n = ints(3)
         if (ints(1) == 2) then
            nshared = nshared + n
         else
            nhelped = nhelped + n
         end if
         nt = size(prob%targets)
         allocate (rs(prob%nres(), n), fs(n), per_test(nt, n), status(n), messages(n))
         if (ints(1) == 2) then
            ! A share of every point's tests (see shared_tests): the first failed test of
            ! each point and the share's times go back too
            allocate (failed(n), seconds(nt))
            seconds = 0.0_dp
            call prob%batch(reshape(reals, [nx, n]), ints(2), rs, fs, per_test, status, messages, &
                            tag, only=ints(4:3 + nt) == 1, failed=failed, seconds=seconds)
         else
            allocate (failed(0), seconds(0))
            call prob%batch(reshape(reals, [nx, n]), ints(2), rs, fs, per_test, status, messages, tag)
         end if
         allocate (character(len=n*message_len) :: text)
         do j = 1, n
            text((j - 1)*message_len + 1:j*message_len) = messages(j)
         end do
         if (ints(1) == 2) then
            call send_packet(owner, tag_help_result, [status, failed], [reshape(rs, [size(rs)]), &
                             reshape(per_test, [size(per_test)]), seconds], text)
         else
            call send_packet(owner, tag_help_result, status, [reshape(rs, [size(rs)]), fs, &
                             reshape(per_test, [size(per_test)])], text)
         end if
         deallocate (rs, fs, per_test, status, messages, text, failed, seconds)
      end do
   end subroutine help_others

   !> When resuming, evaluation k must be at the journal's point (the search is deterministic).
   !> Where the search replayed what fit.cache kept, a step off the journal is the cache's
   !> (its residuals or Jacobians damaged) when the cache holds the journal's point k too,
   !> and the message names it
   subroutine check_replay(self, k, x, error)
      class(fit_objective), intent(in) :: self
      integer, intent(in) :: k
      real(dp), intent(in) :: x(:)
      type(error_type), allocatable, intent(out) :: error
      character(len=:), allocatable :: journal, cache
      if (all(abs(x - self%replay(k)%x) <= 1.0e-12_dp*max(1.0_dp, abs(x)))) return
      journal = journal_name
      if (allocated(self%journal)) journal = self%journal
      cache = journal(:len(journal) - len(journal_name))//cache_name
      if (self%cache_used .and. allocated(self%replay(k)%r)) then
         ! The cache holds the journal's point too: the journal is not what is damaged
         call fatal_error(error, cache//': cannot resume: the residuals or Jacobians replayed '// &
            'from this file led the search off '//journal_name//' at evaluation '//str(k)// &
            ' (the file is damaged); remove it to resume without it (its evaluations simulated '// &
            'again), or start again with --force', stat_input)
      else if (self%cache_used) then
         call fatal_error(error, journal//': cannot resume: evaluation '//str(k)//' was made at '// &
            'other constants than the search replaying '//cache_name//' reached: one of the two '// &
            'files is damaged; remove '//cache_name//' to resume without it, or start again '// &
            'with --force', stat_input)
      else
         call fatal_error(error, journal//': cannot resume: evaluation '//str(k)// &
            ' was made at other constants (did the input change?)', stat_input)
      end if
   end subroutine check_replay

   !> Before a simulation: a stop signal ends the fit here (replayed evaluations go on being
   !> logged, so that what was computed is kept); a replay_only objective ends with
   !> stat_exhausted
   subroutine may_simulate(self, error)
      class(fit_objective), intent(inout) :: self
      type(error_type), allocatable, intent(out) :: error
      if (self%replay_only) then
         call fatal_error(error, 'replay exhausted', stat_exhausted)
         return
      end if
      call check_stop(self, error)
   end subroutine may_simulate

   !> What a replayed evaluation's log says: why it failed when another rank made it
   function replay_message(self, k) result(message)
      class(fit_objective), intent(in) :: self
      integer, intent(in) :: k
      character(len=:), allocatable :: message
      if (allocated(self%replay(k)%message)) then
         message = self%replay(k)%message
      else
         message = 'replayed'
      end if
   end function replay_message

   !> The prefix of the evaluations' names ('' but for a start made on its own)
   function tag_of(self) result(tag)
      class(fit_objective), intent(in) :: self
      character(len=:), allocatable :: tag
      tag = ''
      if (allocated(self%tag)) tag = self%tag
   end function tag_of

   !> A stop signal (SIGTERM from a batch scheduler, Ctrl-C) ends the fit between
   !> evaluations with a note in fit.log; the exit code is 128 + the signal's number
   subroutine check_stop(self, error)
      class(fit_objective), intent(inout) :: self
      type(error_type), allocatable, intent(out) :: error
      integer :: sig
      sig = stop_signal()
      if (sig == 0) return
      call fatal_error(error, 'stopped by signal '//str(sig)//' after '//str(self%nevals)// &
                       ' evaluations; continue with --resume', 128 + sig)
      call self%log%event(error%message)
   end subroutine check_stop

   !> Log one evaluation (with its residuals r, when given, for a resume to replay), count
   !> failures (an error after max_failures in a row), keep the best
   subroutine fit_record(self, x, f, per_test, status, message, error, r)
      class(fit_objective), intent(inout) :: self
      real(dp), intent(in) :: x(:), f, per_test(:)
      integer, intent(in) :: status
      character(len=*), intent(in) :: message
      type(error_type), allocatable, intent(out) :: error
      real(dp), intent(in), optional :: r(:)
      integer :: k
      self%nevals = self%nevals + 1
      k = self%nevals
      if (self%capture) then
         call keep(self, x, f, per_test, status, message, r)
      else
         call self%log%record(k, status, f, per_test, x, self%constants_of(x), error, r)
         if (allocated(error)) return
      end if
      if (k == 1) self%first = f
      if (status /= eval_ok) then
         self%nfail_row = self%nfail_row + 1
         self%nfail_total = self%nfail_total + 1
         if (status == eval_invalid) self%ninvalid_total = self%ninvalid_total + 1
         call self%log%event('evaluation '//str(k)//': penalty '//real_str(f, 'es10.3')//': '// &
                             message)
         if (self%nfail_row >= self%prob%cfg%fit%max_failures) then
            call fatal_error(error, 'fit aborted: '//str(self%nfail_row)// &
               ' failed evaluations in a row (max_failures); last: '//message, stat_failure)
            call self%log%event(error%message)
            return
         end if
      else
         self%nfail_row = 0
      end if
      if (f < self%best) then
         self%best = f
         self%best_x = x
         self%best_per_test = per_test
      end if
      if (associated(self%progress)) call report(self)
   end subroutine fit_record

   !> Keep an evaluation in memory (grown by doubling)
   subroutine keep(self, x, f, per_test, status, message, r)
      class(fit_objective), intent(inout) :: self
      real(dp), intent(in) :: x(:), f, per_test(:)
      integer, intent(in) :: status
      character(len=*), intent(in) :: message
      real(dp), intent(in), optional :: r(:)
      if (.not. allocated(self%kept)) allocate (self%kept(16))
      if (self%nkept == size(self%kept)) call moved_records(self%kept, self%nkept, 2*self%nkept)
      self%nkept = self%nkept + 1
      associate (rec => self%kept(self%nkept))
         rec%status = status
         rec%f = f
         rec%per_test = per_test
         rec%x = x
         if (present(r)) rec%r = r
         rec%message = message
      end associate
   end subroutine keep

   subroutine report(self)
      class(fit_objective), intent(in) :: self
      integer(int64) :: now, rate
      call system_clock(now, rate)
      call self%progress(self%nevals, self%best, real(now - self%clock0, dp)/real(rate, dp))
   end subroutine report

   !> Run the fit of a problem with its &fit settings, logging into dir. With resume, the
   !> journal in dir is replayed first (refused when the fingerprint of the inputs changed);
   !> without resume, an existing journal is an error unless force. constants_file: the
   !> --constants file, part of the fingerprint. progress, when given, hears of every
   !> evaluation. SIGTERM and SIGINT stop the fit between evaluations (see check_stop).
   subroutine run_fit(prob, dir, resume, outcome, error, progress, force, constants_file, auto_resume, &
                      hold_signals)
      type(fit_problem), intent(in) :: prob
      character(len=*), intent(in) :: dir
      logical, intent(in) :: resume
      type(fit_outcome), intent(out) :: outcome
      type(error_type), allocatable, intent(out) :: error
      procedure(progress_interface), optional :: progress
      logical, intent(in), optional :: force
      !> resume when dir holds a journal with records, else start (for job scripts)
      logical, intent(in), optional :: auto_resume
      character(len=*), intent(in), optional :: constants_file
      !> stop signals stay caught past the search: the caller writes the results whole and
      !> then calls release_stop_signals
      logical, intent(in), optional :: hold_signals
      type(fit_objective) :: obj
      type(error_type), allocatable :: close_error
      integer(int64) :: now, rate
      character(len=:), allocatable :: fingerprint, old_fingerprint, changed, journal
      logical :: overwrite, resuming, parallel
      integer :: k
      obj%prob = prob
      allocate (obj%replay(0), obj%replay_jac(0), obj%replay_done(0))
      overwrite = .false.
      if (present(force)) overwrite = force
      if (present(constants_file)) then
         fingerprint = fit_fingerprint(prob%cfg, constants_file)
      else
         fingerprint = fit_fingerprint(prob%cfg, '')
      end if
      journal = join_path(dir, journal_name)
      obj%journal = journal
      resuming = resume
      if (present(auto_resume)) then
         if (auto_resume) resuming = journal_has_records(journal)
      end if
      if (resuming) then
         call read_journal(journal, size(prob%targets), size(prob%idx), obj%replay, &
                           obj%replay_done, old_fingerprint, error)
         if (allocated(error)) return
         if (len_trim(old_fingerprint) == 0) then
            call fatal_error(error, journal//': cannot resume: the file has no fingerprint line '// &
               '(it is not a fit.journal of this usharp); start again with --force', stat_input)
            return
         end if
         if (fingerprint_damaged(journal, old_fingerprint, fingerprint)) then
            call fatal_error(error, journal//': cannot resume: the journal is damaged (its '// &
               'fingerprint line is cut short); start again with --force', stat_input)
            return
         end if
         changed = fingerprint_mismatch(old_fingerprint, fingerprint)
         if (len(changed) > 0) then
            call fatal_error(error, journal//': cannot resume: '//changed// &
               ' changed since the journal was written (start again without --resume, with --force)', &
               stat_input)
            return
         end if
         call read_cache(join_path(dir, cache_name), prob%nres(), obj%replay, obj%replay_jac)
         ! fit.log is written anew as the journal is replayed: the reasons of the penalised
         ! evaluations come from the log it replaces
         call carry_penalty_reasons(join_path(dir, 'fit.log'), obj%replay)
         ! The search replayed alone first, before the logs are started anew: a journal it
         ! cannot follow (damaged, or written from other inputs than its fingerprint names)
         ! is refused with the run's files as they were (a start the journal closes is
         ! taken as it is, where its optimum is one of its evaluations: see closed_start)
         call dry_replay(obj, error)
         if (allocated(error)) return
      else if (.not. overwrite .and. journal_has_records(journal)) then
         call fatal_error(error, journal//': holds the journal of an earlier run; continue it '// &
            'with --resume, or start again and overwrite it with --force', stat_usage)
         return
      end if
      obj%nresumed = size(obj%replay)
      obj%fingerprint = fingerprint
      parallel = n_ranks() > 1 .and. prob%cfg%fit%multistart > 0
      ! Under MPI, rank 0 alone writes the logs, once every rank has read the journal
      call parallel_sync()
      if (.not. is_root()) obj%capture = .true.
      if (is_root()) call obj%log%open(dir, fingerprint, prob%nres(), size(prob%idx), error)
      if (allocated(error)) then
         call obj%log%close()
         return
      end if
      call catch_stop_signals()
      if (size(obj%replay) > 0 .and. .not. parallel) call obj%log%event('resumed: '// &
         str(size(obj%replay))//' evaluations in '//journal_name//', '// &
         str(count([(allocated(obj%replay(k)%r), k=1, size(obj%replay))]))// &
         ' of them with their residual vectors in '//cache_name//'; starts it closes: '// &
         str(size(obj%replay_done))//' (a least-squares search replays those starts whole, and '// &
         'of the start under way the evaluations with residuals)')
      if (present(progress)) obj%progress => progress
      call system_clock(obj%clock0, rate)
      if (parallel) then
         call parallel_search(obj, outcome%opt, outcome%nstarts, error)
      else
         call helped_search(obj, outcome%opt, outcome%nstarts, error)
      end if
      outcome%helped = counts_of_ranks(obj%nhelped)
      outcome%shared = counts_of_ranks(obj%nshared)
      if (.not. is_root()) then
         call release_stop_signals()
         return
      end if
      ! Past the search a signal ends the process at once, unless the caller holds it off
      ! while it writes the results
      if (.not. present(hold_signals)) then
         call release_stop_signals()
      else if (.not. hold_signals) then
         call release_stop_signals()
      end if
      call system_clock(now)
      outcome%seconds = real(now - obj%clock0, dp)/real(rate, dp)
      outcome%f_start = obj%first
      outcome%nfail = obj%nfail_total
      outcome%ninvalid = obj%ninvalid_total
      ! Over ranks, the starts' replays as the journal's dry run found them; in one search,
      ! those made (a journal without its fit.cache replays no residual vector)
      if (parallel) then
         outcome%nreplayed = min(obj%nresumed, obj%nevals)
      else
         outcome%nreplayed = obj%nreplayed
      end if
      outcome%nsimulated = obj%nsimulated
      if (.not. allocated(error)) then
         outcome%opt%nevals = obj%nevals
         outcome%constants = obj%constants_of(outcome%opt%x)
         outcome%per_test = obj%best_per_test
         call obj%log%event('finished: '//outcome%opt%reason//', objective '// &
            real_str(outcome%opt%f, 'es12.5')//' after '//str(outcome%opt%nevals)//' evaluations')
      end if
      call obj%log%close(close_error)
      if (.not. allocated(error) .and. allocated(close_error)) call move_alloc(close_error, error)
   end subroutine run_fit

   !> The search replayed from the journal alone, nothing logged: the error of a replay that
   !> leaves the journal (see check_replay), none where it runs out of records or ends
   subroutine dry_replay(obj, error)
      type(fit_objective), intent(in) :: obj
      type(error_type), allocatable, intent(out) :: error
      type(fit_objective) :: dry
      type(optimum_type) :: one
      type(error_type), allocatable :: e
      integer :: n
      if (size(obj%replay) == 0) return
      dry = dry_worker(obj)
      call search(dry, one, n, e)
      if (.not. allocated(e)) return
      if (e%stat == stat_input) call move_alloc(e, error)
   end subroutine dry_replay

   !> The reasons that the fit.log at path gives for penalised evaluations ("evaluation k:
   !> penalty f: reason"), into the journal's records that have none
   subroutine carry_penalty_reasons(path, records)
      character(len=*), intent(in) :: path
      type(journal_record), intent(inout) :: records(:)
      character(len=:), allocatable :: line
      integer :: unit, ios, k, at, colon
      open (newunit=unit, file=path, status='old', action='read', iostat=ios)
      if (ios /= 0) return
      do
         call read_line(unit, line, ios)
         if (ios /= 0) exit
         if (index(line, 'evaluation ') /= 1) cycle
         at = index(line, ': penalty ')
         if (at == 0) cycle
         read (line(12:at - 1), *, iostat=ios) k
         if (ios /= 0 .or. k < 1 .or. k > size(records)) cycle
         colon = index(line(at + 10:), ': ')
         if (colon == 0) cycle
         if (.not. allocated(records(k)%message)) records(k)%message = line(at + 10 + colon + 1:)
      end do
      close (unit)
   end subroutine carry_penalty_reasons

   !> Whether a journal file holds at least one evaluation (a line besides the fingerprint)
   logical function journal_has_records(path) result(has)
      character(len=*), intent(in) :: path
      integer :: unit, ios
      character(len=1) :: c
      has = .false.
      if (.not. file_exists(path)) return
      open (newunit=unit, file=path, status='old', action='read', iostat=ios)
      if (ios /= 0) return
      do
         read (unit, '(a)', iostat=ios) c
         if (ios /= 0) exit
         if (c /= '#') then
            has = .true.
            exit
         end if
      end do
      close (unit)
   end function journal_has_records

   !> The fingerprint of everything that decides a fit's result: the program version, its
   !> build (see build_id), the FNV-1a 64-bit hashes of the input file's, the constants
   !> file's and every test's data file's contents and of every test's control history
   !> (which a history file decides), as space-separated name=value items
   function fit_fingerprint(cfg, constants_file) result(fp)
      type(run_config), intent(in) :: cfg
      character(len=*), intent(in) :: constants_file
      character(len=:), allocatable :: fp
      integer :: i
      fp = 'version='//usharp_version_string//' build='//build_id()//' input='//hashed(cfg%path)
      if (len_trim(constants_file) > 0) fp = fp//' constants='//hashed(constants_file)
      do i = 1, size(cfg%tests)
         ! The control history itself (a history file's contents reach the fit only through it)
         if (allocated(cfg%tests(i)%hist%t)) fp = fp//' history:'//trim(cfg%tests(i)%name)//'='// &
            hash_hex(hash_text(history_bytes(cfg%tests(i)%hist%t, cfg%tests(i)%hist%v)))
         if (allocated(cfg%tests(i)%data%file)) then
            if (len_trim(cfg%tests(i)%data%file) > 0) &
               fp = fp//' data:'//trim(cfg%tests(i)%name)//'='//hashed(cfg%tests(i)%data%file)
         end if
         ! The measured peaks (target 'peaks' or 'both') are read from a file of their own
         if (allocated(cfg%tests(i)%peak_file)) then
            if (len_trim(cfg%tests(i)%peak_file) > 0) &
               fp = fp//' peaks:'//trim(cfg%tests(i)%name)//'='//hashed(cfg%tests(i)%peak_file)
         end if
      end do
   contains
      pure function history_bytes(t, v) result(bytes)
         real(dp), intent(in) :: t(:), v(:)
         character(len=8*(size(t) + size(v))) :: bytes
         bytes = transfer([t, v], bytes)
      end function history_bytes
      function hashed(path) result(hex)
         character(len=*), intent(in) :: path
         character(len=:), allocatable :: hex
         integer(int64) :: h
         logical :: ok
         call file_hash(path, h, ok)
         if (ok) then
            hex = hash_hex(h)
         else
            hex = 'unreadable'
         end if
      end function hashed
   end function fit_fingerprint
   !> The configured method from the input's start, or from each multi-start point (a Latin
   !> hypercube over the box, in log10 of the constants); the best result wins
   !> (first to last: only those starts, each from where the previous one left the objective)
   subroutine search(obj, opt, nstarts, error, first, last)
      type(fit_objective), intent(inout) :: obj
      type(optimum_type), intent(out) :: opt
      integer, intent(out) :: nstarts
      type(error_type), allocatable, intent(out) :: error
      integer, intent(in), optional :: first, last
      type(optimum_type) :: one
      type(rng_type) :: rng
      real(dp), allocatable :: u(:, :), lo(:), hi(:), blo(:), bhi(:), x0(:)
      integer :: s, n, s1, s2, k
      associate (fc => obj%prob%cfg%fit, idx => obj%prob%idx)
         n = size(idx)
         lo = log10_dp(fc%lower(idx))
         hi = log10_dp(fc%upper(idx))
         blo = log10_dp(fc%box_lower(idx))
         bhi = log10_dp(fc%box_upper(idx))
         nstarts = max(1, fc%multistart)
         if (fc%multistart > 0) then
            call rng%seed(fc%seed)
            call latin_hypercube(rng, n, fc%multistart, u)
         end if
         s1 = 1
         s2 = nstarts
         if (present(first)) s1 = first
         if (present(last)) s2 = last
         if (.not. allocated(obj%start_eval)) then
            allocate (obj%start_eval(nstarts), obj%start_sens(nstarts))
            obj%start_eval = 0
            obj%start_sens = 0
         end if
         do s = s1, s2
            obj%start_now = s
            obj%start_eval(s) = obj%nevals + 1
            obj%start_sens(s) = obj%nsens + 1
            if (fc%multistart > 0) then
               x0 = blo + u(:, s)*(bhi - blo)
               if (.not. fc%log_search) x0 = pow10_dp(x0)
               call obj%log%event('multi-start '//str(s)//' of '//str(nstarts)//' from evaluation '// &
                                  str(obj%nevals + 1))
            else
               x0 = obj%prob%start_point()
            end if
            ! fit.cache keeps the start under way only
            if (.not. obj%capture) call obj%log%new_cache(error)
            if (allocated(error)) return
            k = closed_start(obj, s)
            if (k > 0) then
               call replay_start(obj, obj%replay_done(k), one, error)
            else
               call one_search()
            end if
            if (allocated(error)) return
            obj%closed = start_done(s, obj%start_eval(s), obj%nevals, obj%nsens - obj%start_sens(s) + 1, one)
            if (.not. obj%capture) call obj%log%start_done(s, obj%closed%first, obj%closed%last, &
                                                           obj%closed%njac, one, error)
            if (allocated(error)) return
            if (s == s1 .or. one%f < opt%f) opt = one
         end do
         if (fc%multistart > 0) opt%reason = 'best of '//str(nstarts)//' starts: '//opt%reason
      end associate
   contains
      !> The configured method from x0
      subroutine one_search()
         associate (fc => obj%prob%cfg%fit)
            select case (fc%method)
            case ('lm')
               call levenberg_marquardt(obj, x0, lo, hi, fc%fd_step, fc%eps, fc%itermax, fc%max_evals, &
                                        one, error)
            case ('nelder-mead')
               call nelder_mead(obj, x0, lo, hi, fc%rho, fc%eps, fc%max_evals, one, error)
            case ('anneal')
               call anneal(obj, x0, lo, hi, fc%anneal_t0, fc%anneal_rt, fc%seed + s, fc%eps, &
                           fc%max_evals, one, error)
            case default
               call hooke_jeeves(obj, x0, fc%rho, fc%eps, fc%itermax, fc%max_evals, one, error)
            end select
         end associate
      end subroutine one_search
   end subroutine search

   !> The index in obj%replay_done of start s when the journal closes it at the evaluation
   !> the search has reached (0: it does not). A closing line whose optimum is none of the
   !> start's evaluations (every optimiser ends at a point it evaluated) is damaged and
   !> closes nothing: the start's search is replayed instead
   pure integer function closed_start(obj, s) result(k)
      type(fit_objective), intent(in) :: obj
      integer, intent(in) :: s
      integer :: j, i
      k = 0
      do j = 1, size(obj%replay_done)
         associate (d => obj%replay_done(j))
            if (d%start /= s .or. d%first /= obj%nevals + 1 .or. d%last > size(obj%replay)) cycle
            do i = d%first, d%last
               if (obj%replay(i)%f == d%opt%f .and. all(obj%replay(i)%x == d%opt%x)) then
                  k = j
                  return
               end if
            end do
         end associate
      end do
   end function closed_start

   !> A start the journal closes, taken from it as it was made: its evaluations logged again
   !> (with the residuals and Jacobians fit.cache held, the last start's of a finished fit, so
   !> that a resume keeps them) and the optimum it reached, no search run and nothing
   !> simulated (a finished start needs nothing of fit.cache)
   subroutine replay_start(obj, done, opt, error)
      type(fit_objective), intent(inout) :: obj
      type(start_done), intent(in) :: done
      type(optimum_type), intent(out) :: opt
      type(error_type), allocatable, intent(out) :: error
      type(cached_jacobian), allocatable :: none(:)
      integer :: k
      do k = done%first, done%last
         associate (rec => obj%replay(k))
            ! With the residuals fit.cache held (a finished fit's last start): they stay in
            ! it, which a resume of a finished fit had cut to its header
            if (allocated(rec%r)) then
               call obj%record(rec%x, rec%f, rec%per_test, rec%status, replay_message(obj, k), error, &
                               rec%r)
            else
               call obj%record(rec%x, rec%f, rec%per_test, rec%status, replay_message(obj, k), error)
            end if
         end associate
         if (allocated(error)) return
         obj%nreplayed = obj%nreplayed + 1
      end do
      ! Its Jacobians keep their numbers, not kept (a capturing objective's are counted by
      ! their place in kept_jac); those fit.cache held stay in it, as the residuals above
      if (obj%capture) then
         allocate (none(done%njac))
         obj%kept_jac = [obj%kept_jac, none]
      else
         do k = obj%nsens + 1, min(obj%nsens + done%njac, size(obj%replay_jac))
            if (.not. allocated(obj%replay_jac(k)%x)) cycle
            call obj%log%record_jacobian(k, obj%replay_jac(k)%x, obj%replay_jac(k)%jac, error)
            if (allocated(error)) return
         end do
      end if
      obj%nsens = obj%nsens + done%njac
      opt = done%opt
   end subroutine replay_start

   !> One search, made by rank 0 with its logs written as it goes; the other ranks help with
   !> its batches of points (the columns of a difference Jacobian, see shared_batch). The
   !> direct searches evaluate one point at a time: they are rank 0's alone.
   subroutine helped_search(obj, opt, nstarts, error)
      type(fit_objective), intent(inout) :: obj
      type(optimum_type), intent(out) :: opt
      integer, intent(out) :: nstarts
      type(error_type), allocatable, intent(out) :: error
      type(task_deal), target :: deal
      ! No task to deal: the deal only pairs rank 0 with its helpers
      call deal%open(1, 0)
      nstarts = 1
      if (is_root()) then
         obj%deal => deal
         call search(obj, opt, nstarts, error)
         call end_helped(obj)
      end if
      call help_others(obj%prob, deal, obj%nhelped, obj%nshared)
      call deal%close()
   end subroutine helped_search

   !> The starts of a multi-start fit spread over the MPI ranks in chunks (see tasks_per_share),
   !> each start to the next rank that is free (OpenMP threads inside each start), each
   !> searched on its own with its evaluations kept. A rank sends each start it finishes to
   !> rank 0 at once, and rank 0, between its own starts, runs the search again over the
   !> starts in their order as far as they are complete, replaying them into the logs, so
   !> that the logs, the journal and the result are those of one process while the other
   !> ranks work on. Starts a journal holds (resume) are taken from it, whatever number of
   !> ranks wrote it; a start it holds in part goes on from there. After a stop (a signal,
   !> too many failures) rank 0 goes on from the first start that stopped, as one process
   !> would, after the starts it has logged.
   subroutine parallel_search(obj, opt, nstarts, error)
      type(fit_objective), intent(inout) :: obj
      type(optimum_type), intent(out) :: opt
      integer, intent(out) :: nstarts
      type(error_type), allocatable, intent(out) :: error
      type(start_log), allocatable, asynchronous :: logs(:)
      type(fit_objective) :: dry, w, live
      type(optimum_type) :: one, best
      type(error_type), allocatable :: e, live_error
      type(task_deal), target :: deal
      integer, allocatable :: owner(:)
      logical, allocatable :: ready(:), headed(:)
      integer :: np, s, s0, s1, t, n, first_open, last, nsim, chunk, next, nfreed
      logical :: streaming, stopped
      np = n_ranks()
      nstarts = max(1, obj%prob%cfg%fit%multistart)
      allocate (logs(nstarts), owner(nstarts), ready(nstarts), headed(nstarts))
      do s = 1, nstarts
         allocate (logs(s)%recs(0), logs(s)%jacs(0))
      end do
      ready = .false.
      headed = .false.
      first_open = 1
      if (size(obj%replay) > 0) then
         ! Replay the journal alone to find where each start's evaluations lie in it
         dry = dry_worker(obj)
         call search(dry, one, n, e)
         first_open = nstarts + 1
         if (allocated(e)) first_open = dry%start_now
         do s = 1, min(dry%start_now, nstarts)
            last = dry%nkept
            if (s < dry%start_now) last = dry%start_eval(s + 1) - 1
            logs(s)%recs = dry%kept(dry%start_eval(s):last)
            last = size(dry%kept_jac)
            if (s < dry%start_now) last = dry%start_sens(s + 1) - 1
            logs(s)%jacs = dry%kept_jac(dry%start_sens(s):last)
         end do
         obj%nresumed = dry%nkept
         ready(:first_open - 1) = .true.
      end if
      ! Rank 0 replays the starts into the logs on a copy of the objective (the journal's
      ! records are in logs now); it takes each start's records as the start is replayed
      streaming = is_root()
      next = 1
      nfreed = 0
      if (streaming) then
         deallocate (obj%replay, obj%replay_jac)
         allocate (obj%replay(0), obj%replay_jac(0))
         live = obj
         live%replay_only = .true.
         ! Progress is heard from the starts as rank 0 searches them, not from their replay
         live%progress => null()
         if (obj%nresumed > 0) call live%log%event('resumed: replaying '//str(obj%nresumed)// &
                                                   ' evaluations from '//journal_name)
         call replay_ready()
      end if
      chunk = np*tasks_per_share(nstarts - first_open + 1, np)
      do s0 = first_open, nstarts, chunk
         s1 = min(s0 + chunk - 1, nstarts)
         ! The chunk's starts dealt to the ranks as they become free, each searched on its
         ! own; after a stop this rank takes no more
         logs(s0:s1)%stat = stat_not_run
         call deal%open(s0, s1)
         do
            if (stop_signal() /= 0) exit
            s = deal%take()
            if (s == 0) exit
            w = worker(obj)
            w%replay = logs(s)%recs
            w%replay_jac = logs(s)%jacs
            w%tag = 'start'//str(s)//'-'
            w%deal => deal
            if (is_root() .and. associated(obj%progress)) w%progress => obj%progress
            call search(w, one, n, e, s, s)
            call end_helped(w)
            call moved_records(w%kept, w%nkept, w%nkept)
            call move_alloc(w%kept, logs(s)%recs)
            call move_alloc(w%kept_jac, logs(s)%jacs)
            logs(s)%nsimulated = w%nsimulated
            logs(s)%stat = 0
            if (allocated(e)) logs(s)%stat = e%stat
            call close_log(logs(s), w%closed, s == nstarts)
            if (is_root()) then
               ready(s) = .true.
               call take_arrived(.false.)
               call replay_ready()
            else
               call send_start(s)
            end if
            if (allocated(e)) exit
         end do
         ! Out of starts: help the ranks still at work with their batches until all are out
         call help_others(obj%prob, deal, obj%nhelped, obj%nshared)
         call deal%close()
         owner(s0:s1) = ranks_that_ran(logs(s0:s1)%stat /= stat_not_run)
         stopped = any(owner(s0:s1) < 0)
         stopped = any_rank(stopped .or. any(logs(s0:s1)%stat /= 0 .and. owner(s0:s1) == this_rank()))
         if (is_root()) then
            ! Every start another rank ran in this chunk, as it arrives
            do while (any(owner(s0:s1) > 0 .and. .not. headed(s0:s1)))
               call take_arrived(.true.)
            end do
            do t = s0, s1
               if (owner(t) > 0 .and. .not. ready(t)) then
                  call logs(t)%moving%wait()
                  call unpack_start(t)
               end if
            end do
            call replay_ready()
         else
            do t = s0, s1
               if (owner(t) == this_rank()) call logs(t)%moving%wait()
            end do
         end if
         if (stopped) exit
      end do
      if (.not. is_root()) return
      nsim = sum(logs%nsimulated)
      if (allocated(live_error)) then
         call move_alloc(live_error, error)
         obj%nsimulated = obj%nsimulated + nsim
         ! The logs as the replay left them (it began fit.cache anew): run_fit closes these
         obj%log = live%log
         return
      end if
      if (next <= nstarts) then
         ! A start stopped: the search goes on from it as one process would, replaying what
         ! the ranks made of it and simulating the rest here (unless the stop is this rank's
         ! too, which ends it there). The logs written so far stay as they are: rewriting
         ! them would leave a window in which a kill (a scheduler's, after its grace time)
         ! takes the journal with it
         call append_starts(logs(next:), live%replay, live%replay_jac)
         live%replay_only = .false.
         call search(live, one, n, error, next, nstarts)
         if (.not. allocated(error)) then
            if (next == 1 .or. one%f < best%f) best = one
         end if
      end if
      deallocate (live%replay, live%replay_jac)
      allocate (live%replay(0), live%replay_jac(0))
      live%nhelped = obj%nhelped
      live%nshared = obj%nshared
      obj = live
      obj%replay_only = .false.
      opt = best
      obj%nsimulated = obj%nsimulated + nsim

   contains

      !> Rank 0: replay the starts from next on while they are complete (not past a start
      !> that stopped, or after a failed write)
      subroutine replay_ready()
         type(error_type), allocatable :: err
         type(optimum_type) :: got
         type(start_done) :: done
         integer :: nn, k
         do while (streaming .and. next <= nstarts)
            if (.not. ready(next)) exit
            if (logs(next)%stat /= 0) then
               streaming = .false.
               exit
            end if
            if (logs(next)%closed) then
               ! Closed where its evaluations fall among the whole fit's, as a journal
               ! would close it: logged from its records, its search not run again
               done = logs(next)%done
               done%first = live%nevals + 1
               done%last = live%nevals + size(logs(next)%recs)
               live%replay_done = [live%replay_done, done]
            end if
            call append_starts(logs(next:next), live%replay, live%replay_jac)
            call search(live, got, nn, err, next, next)
            if (allocated(err)) then
               streaming = .false.
               call move_alloc(err, live_error)
               exit
            end if
            if (next == 1 .or. got%f < best%f) best = got
            next = next + 1
            ! The residual vectors replayed are not read again: their memory serves the
            ! starts still to come
            do k = nfreed + 1, min(live%nevals, size(live%replay))
               if (allocated(live%replay(k)%r)) deallocate (live%replay(k)%r)
            end do
            nfreed = max(nfreed, min(live%nevals, size(live%replay)))
         end do
      end subroutine replay_ready

      !> Another rank: start sending start s to rank 0 (its header, then its fields in order:
      !> each record's, and a closed start's optimum, or the Jacobians and residual vectors
      !> of one rank 0 searches again)
      subroutine send_start(s)
         integer, intent(in) :: s
         integer :: k, nrec, njac, pos, at, nmsg, nx, ntest, m, n_r, nreason
         nx = size(obj%prob%idx)
         ntest = size(obj%prob%targets)
         m = obj%prob%nres()
         associate (sl => logs(s))
            nrec = size(sl%recs)
            njac = size(sl%jacs)
            nmsg = 0
            do k = 1, nrec
               nmsg = nmsg + len(sl%recs(k)%message)
            end do
            n_r = 0
            do k = 1, nrec
               if (allocated(sl%recs(k)%r)) n_r = n_r + 1
            end do
            nreason = 0
            if (sl%closed) nreason = len(sl%done%opt%reason)
            allocate (sl%ints(nhead + 3*nrec), sl%reals(nrec*(1 + ntest + nx) + data_size(sl%closed, njac, n_r)))
            allocate (character(len=nmsg + nreason) :: sl%text)
            sl%ints(1:nhead) = [s, nrec, njac, sl%stat, sl%nsimulated, merge(1, 0, sl%closed), &
                                sl%done%opt%nevals, sl%done%opt%iterations, nreason]
            pos = 0
            at = 0
            do k = 1, nrec
               associate (rec => sl%recs(k))
                  sl%ints(nhead + 3*(k - 1) + 1:nhead + 3*k) = [rec%status, merge(1, 0, allocated(rec%r)), &
                                                                len(rec%message)]
                  sl%reals(pos + 1:pos + 1 + ntest + nx) = [rec%f, rec%per_test, rec%x]
                  pos = pos + 1 + ntest + nx
                  sl%text(at + 1:at + len(rec%message)) = rec%message
                  at = at + len(rec%message)
               end associate
            end do
            if (sl%closed) then
               sl%reals(pos + 1:pos + 1 + nx) = [sl%done%opt%f, sl%done%opt%x]
               sl%text(at + 1:at + nreason) = sl%done%opt%reason
            else
               do k = 1, njac
                  sl%reals(pos + 1:pos + nx + m*nx) = [sl%jacs(k)%x, reshape(sl%jacs(k)%jac, [m*nx])]
                  pos = pos + nx + m*nx
               end do
               ! Each residual vector freed once packed: its memory serves the next start
               do k = 1, nrec
                  if (allocated(sl%recs(k)%r)) then
                     sl%reals(pos + 1:pos + m) = sl%recs(k)%r
                     pos = pos + m
                     deallocate (sl%recs(k)%r)
                  end if
               end do
            end if
            call post_send(sl%ints, tag_head, sl%moving)
            call post_send(sl%reals, tag_data, sl%moving)
            call post_send(sl%text, tag_data, sl%moving)
         end associate
      end subroutine send_start

      !> The reals sent after a start's records: a closed start's optimum (f and x), or njac
      !> Jacobians and n_r residual vectors
      pure integer function data_size(closed, njac, n_r) result(n)
         logical, intent(in) :: closed
         integer, intent(in) :: njac, n_r
         if (closed) then
            n = 1 + size(obj%prob%idx)
         else
            n = njac*(size(obj%prob%idx)*(1 + obj%prob%nres())) + n_r*obj%prob%nres()
         end if
      end function data_size

      !> Rank 0: the headers of starts that have arrived (wait: at least one), each start's
      !> data received into its records as they come; the starts whose data are complete
      subroutine take_arrived(wait)
         logical, intent(in) :: wait
         integer :: from, nints, s, k, nrec, nmsg, n_r
         integer, allocatable :: head(:)
         logical :: block
         block = wait
         do while (header_waiting(tag_head, block, from, nints))
            block = .false.
            allocate (head(nints))
            call receive_header(head, from, tag_head)
            s = head(1)
            nrec = head(2)
            associate (sl => logs(s))
               call move_alloc(head, sl%ints)
               sl%stat = sl%ints(4)
               sl%nsimulated = sl%ints(5)
               sl%closed = sl%ints(6) == 1
               nmsg = sl%ints(9)
               do k = 1, nrec
                  nmsg = nmsg + sl%ints(nhead + 3*k)
               end do
               deallocate (sl%recs, sl%jacs)
               allocate (sl%recs(nrec), sl%jacs(sl%ints(3)))
               n_r = 0
               do k = 1, nrec
                  n_r = n_r + sl%ints(nhead + 3*(k - 1) + 2)
               end do
               allocate (sl%reals(nrec*(1 + size(obj%prob%targets) + size(obj%prob%idx)) + &
                                  data_size(sl%closed, sl%ints(3), n_r)))
               allocate (character(len=nmsg) :: sl%text)
               call post_receive(sl%reals, from, tag_data, sl%moving)
               call post_receive(sl%text, from, tag_data, sl%moving)
            end associate
            headed(s) = .true.
         end do
         do s = 1, nstarts
            if (headed(s) .and. .not. ready(s)) then
               if (logs(s)%moving%done()) call unpack_start(s)
            end if
         end do
      end subroutine take_arrived

      !> Rank 0: the fields of start s, received, into its records
      subroutine unpack_start(s)
         integer, intent(in) :: s
         integer :: k, pos, at, nmsg, nx, ntest, m
         nx = size(obj%prob%idx)
         ntest = size(obj%prob%targets)
         m = obj%prob%nres()
         associate (sl => logs(s))
            pos = 0
            at = 0
            do k = 1, size(sl%recs)
               associate (rec => sl%recs(k), meta => sl%ints(nhead + 3*(k - 1) + 1:nhead + 3*k))
                  rec%status = meta(1)
                  rec%f = sl%reals(pos + 1)
                  rec%per_test = sl%reals(pos + 2:pos + 1 + ntest)
                  rec%x = sl%reals(pos + 2 + ntest:pos + 1 + ntest + nx)
                  pos = pos + 1 + ntest + nx
                  nmsg = meta(3)
                  rec%message = sl%text(at + 1:at + nmsg)
                  at = at + nmsg
               end associate
            end do
            if (sl%closed) then
               ! Its Jacobians' places only (see close_log)
               sl%done = start_done(s, 1, size(sl%recs), size(sl%jacs), &
                                    optimum_type(sl%reals(pos + 2:pos + 1 + nx), sl%reals(pos + 1), &
                                                 sl%ints(7), sl%ints(8), sl%text(at + 1:at + sl%ints(9))))
            else
               do k = 1, size(sl%jacs)
                  sl%jacs(k)%x = sl%reals(pos + 1:pos + nx)
                  sl%jacs(k)%jac = reshape(sl%reals(pos + nx + 1:pos + nx + m*nx), [m, nx])
                  pos = pos + nx + m*nx
               end do
               do k = 1, size(sl%recs)
                  if (sl%ints(nhead + 3*(k - 1) + 2) == 1) then
                     sl%recs(k)%r = sl%reals(pos + 1:pos + m)
                     pos = pos + m
                  end if
               end do
            end if
            deallocate (sl%ints, sl%reals, sl%text)
         end associate
         ready(s) = .true.
      end subroutine unpack_start
   end subroutine parallel_search

   !> An ended start other than the fit's last, made ready for rank 0 to log from its records
   !> and its optimum (replay_start) instead of searching it again: its residual vectors and
   !> Jacobians are dropped (the Jacobians' places stay, so that a later start's keep their
   !> numbers), and nothing of them travels between ranks. The last start keeps them: fit.cache
   !> holds them when the fit ends, as one process leaves it. A start that stopped keeps them
   !> for the search that goes on from it.
   pure subroutine close_log(sl, done, last)
      type(start_log), intent(inout) :: sl
      type(start_done), intent(in) :: done
      logical, intent(in) :: last
      integer :: k, njac
      if (sl%stat /= 0 .or. last) return
      sl%closed = .true.
      sl%done = done
      if (.not. allocated(sl%done%opt%reason)) sl%done%opt%reason = ''
      do k = 1, size(sl%recs)
         if (allocated(sl%recs(k)%r)) deallocate (sl%recs(k)%r)
      end do
      njac = size(sl%jacs)
      deallocate (sl%jacs)
      allocate (sl%jacs(njac))
   end subroutine close_log

   !> Append the starts' evaluations to recs and jacs in the order of the starts, up to the
   !> first start that stopped. Everything is moved, not copied (a start's residual vectors
   !> may take hundreds of megabytes, and rank 0 appends start after start): the logs are
   !> not needed again, and the records already in recs stay where they are
   subroutine append_starts(logs, recs, jacs)
      type(start_log), intent(inout) :: logs(:)
      type(journal_record), allocatable, intent(inout) :: recs(:)
      type(cached_jacobian), allocatable, intent(inout) :: jacs(:)
      type(journal_record), allocatable :: old(:)
      type(cached_jacobian), allocatable :: old_jacs(:)
      integer :: s, j, k, kj, last
      last = size(logs)
      do s = 1, size(logs)
         if (logs(s)%stat /= 0) then
            last = s
            exit
         end if
      end do
      if (.not. allocated(recs)) allocate (recs(0))
      if (.not. allocated(jacs)) allocate (jacs(0))
      call move_alloc(recs, old)
      call move_alloc(jacs, old_jacs)
      allocate (recs(size(old) + sum([(size(logs(s)%recs), s=1, last)])), &
                jacs(size(old_jacs) + sum([(size(logs(s)%jacs), s=1, last)])))
      do k = 1, size(old)
         call move_record(old(k), recs(k))
      end do
      do k = 1, size(old_jacs)
         call move_jacobian(old_jacs(k), jacs(k))
      end do
      k = size(old)
      kj = size(old_jacs)
      do s = 1, last
         do j = 1, size(logs(s)%recs)
            k = k + 1
            call move_record(logs(s)%recs(j), recs(k))
         end do
         do j = 1, size(logs(s)%jacs)
            kj = kj + 1
            call move_jacobian(logs(s)%jacs(j), jacs(kj))
         end do
      end do
   end subroutine append_starts

   !> recs resized to n, its first nkept records moved, not copied (a residual vector of the
   !> Alloy 617 fit is 56 kB, and a start keeps some 400)
   pure subroutine moved_records(recs, nkept, n)
      type(journal_record), allocatable, intent(inout) :: recs(:)
      integer, intent(in) :: nkept, n
      type(journal_record), allocatable :: moved(:)
      integer :: k
      allocate (moved(n))
      do k = 1, nkept
         call move_record(recs(k), moved(k))
      end do
      call move_alloc(moved, recs)
   end subroutine moved_records

   !> Move one record's fields into another (no copy of its residual vector)
   pure subroutine move_record(from, to)
      type(journal_record), intent(inout) :: from
      type(journal_record), intent(out) :: to
      to%status = from%status
      to%f = from%f
      if (allocated(from%per_test)) call move_alloc(from%per_test, to%per_test)
      if (allocated(from%x)) call move_alloc(from%x, to%x)
      if (allocated(from%r)) call move_alloc(from%r, to%r)
      if (allocated(from%message)) call move_alloc(from%message, to%message)
   end subroutine move_record

   !> Move one cached Jacobian into another
   pure subroutine move_jacobian(from, to)
      type(cached_jacobian), intent(inout) :: from
      type(cached_jacobian), intent(out) :: to
      if (allocated(from%x)) call move_alloc(from%x, to%x)
      if (allocated(from%jac)) call move_alloc(from%jac, to%jac)
   end subroutine move_jacobian

   !> An objective for one start on its own: the fit's problem, nothing replayed, nothing logged
   function worker(obj) result(w)
      type(fit_objective), intent(in) :: obj
      type(fit_objective) :: w
      w%prob = obj%prob
      if (allocated(obj%journal)) w%journal = obj%journal
      w%capture = .true.
      allocate (w%replay(0), w%replay_jac(0), w%kept_jac(0), w%replay_done(0))
      w%clock0 = obj%clock0
   end function worker

   !> A worker that replays obj's journal (its records, cached Jacobians and closed starts)
   !> and stops where a simulation would be needed: the search's dry run
   function dry_worker(obj) result(w)
      type(fit_objective), intent(in) :: obj
      type(fit_objective) :: w
      w = worker(obj)
      w%replay = obj%replay
      w%replay_jac = obj%replay_jac
      w%replay_done = obj%replay_done
      w%replay_only = .true.
   end function dry_worker
end module usharp_fit
