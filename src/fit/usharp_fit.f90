!> A fit: the objective of a fit problem wrapped with the logs, the journal replay for
!> --resume, the failure count, and a progress report to a caller-supplied procedure
!> (the library itself never prints)
module usharp_fit
   use, intrinsic :: iso_fortran_env, only: int64
   use usharp_kinds, only: dp
   use usharp_error, only: error_type, fatal_error, stat_failure, stat_input
   use usharp_strings, only: str, real_str
   use usharp_miller, only: get_constant, constant_names
   use usharp_objective, only: fit_problem, eval_ok, eval_invalid, message_len
   use usharp_optimiser, only: least_squares_type, optimum_type
   use usharp_hooke_jeeves, only: hooke_jeeves
   use usharp_levenberg, only: levenberg_marquardt
   use usharp_nelder_mead, only: nelder_mead
   use usharp_annealing, only: anneal
   use usharp_sampling, only: latin_hypercube
   use usharp_rng, only: rng_type
   use usharp_fit_log, only: fit_log, journal_record, read_journal, journal_name
   use usharp_filesys, only: join_path
   implicit none
   private

   public :: fit_objective, run_fit, fit_outcome, progress_interface


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
      integer :: nevals = 0
      integer :: nsens = 0              !< sensitivity Jacobians (one simulation each)
      integer :: nfail_row = 0          !< failures in a row
      integer :: nfail_total = 0
      integer :: ninvalid_total = 0
      real(dp) :: best = huge(1.0_dp)
      real(dp) :: first = huge(1.0_dp)
      real(dp), allocatable :: best_per_test(:)
      real(dp), allocatable :: best_x(:)
      procedure(progress_interface), pointer, nopass :: progress => null()
      integer(int64) :: clock0 = 0
   contains
      procedure :: eval => fit_eval
      procedure :: residuals => fit_residuals
      procedure :: jacobian => fit_jacobian
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
      integer :: nstarts = 1  !< local searches run (multi-start)
      real(dp) :: seconds = 0.0_dp
   end type fit_outcome

contains

   !> Fitted constants in physical units for a search point x
   pure function fit_constants_of(self, x) result(c)
      class(fit_objective), intent(in) :: self
      real(dp), intent(in) :: x(:)
      real(dp) :: c(size(x))
      c = x
      if (self%prob%cfg%fit%log_search) c = 10.0_dp**x
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
         message = 'replayed'
      else
         call self%prob%evaluate(x, f, per_test, status, message, str(k))
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
      done = .false.
      if (self%prob%cfg%fit%jacobian /= 'sensitivity') return
      call self%prob%jacobian(x, jac, done)
      if (done) self%nsens = self%nsens + 1
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
      integer :: status(size(xs, 2)), j, k0
      character(len=message_len) :: messages(size(xs, 2))
      k0 = self%nevals
      do j = 1, size(xs, 2)
         if (k0 + j <= size(self%replay)) call check_replay(self, k0 + j, xs(:, j), error)
         if (allocated(error)) return
      end do
      call self%prob%batch(xs, k0, rs, fs, per_test, status, messages)
      do j = 1, size(xs, 2)
         call self%record(xs(:, j), fs(j), per_test(:, j), status(j), trim(messages(j)), error)
         if (allocated(error)) return
         ok(j) = status(j) == eval_ok
      end do
   end subroutine fit_residuals

   !> When resuming, evaluation k must be at the journal's point (the search is deterministic)
   subroutine check_replay(self, k, x, error)
      class(fit_objective), intent(in) :: self
      integer, intent(in) :: k
      real(dp), intent(in) :: x(:)
      type(error_type), allocatable, intent(out) :: error
      if (any(abs(x - self%replay(k)%x) > 1.0e-12_dp*max(1.0_dp, abs(x)))) then
         call fatal_error(error, 'cannot resume: evaluation '//str(k)//' of '// &
            journal_name//' was made at other constants (did the input change?)', stat_input)
      end if
   end subroutine check_replay

   !> Log one evaluation, count failures (an error after max_failures in a row), keep the best
   subroutine fit_record(self, x, f, per_test, status, message, error)
      class(fit_objective), intent(inout) :: self
      real(dp), intent(in) :: x(:), f, per_test(:)
      integer, intent(in) :: status
      character(len=*), intent(in) :: message
      type(error_type), allocatable, intent(out) :: error
      integer :: k
      self%nevals = self%nevals + 1
      k = self%nevals
      call self%log%record(k, status, f, per_test, x, self%constants_of(x))
      if (k == 1) self%first = f
      if (status /= eval_ok) then
         self%nfail_row = self%nfail_row + 1
         self%nfail_total = self%nfail_total + 1
         if (status == eval_invalid) self%ninvalid_total = self%ninvalid_total + 1
         if (k > size(self%replay)) call self%log%event('evaluation '//str(k)//': penalty '// &
            real_str(f, 'es10.3')//': '//message)
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

   subroutine report(self)
      class(fit_objective), intent(in) :: self
      integer(int64) :: now, rate
      call system_clock(now, rate)
      call self%progress(self%nevals, self%best, real(now - self%clock0, dp)/real(rate, dp))
   end subroutine report

   !> Run the fit of a problem with its &fit settings, logging into dir. With resume, the
   !> journal in dir is replayed first. progress, when given, hears of every evaluation.
   subroutine run_fit(prob, dir, resume, outcome, error, progress)
      type(fit_problem), intent(in) :: prob
      character(len=*), intent(in) :: dir
      logical, intent(in) :: resume
      type(fit_outcome), intent(out) :: outcome
      type(error_type), allocatable, intent(out) :: error
      procedure(progress_interface), optional :: progress
      type(fit_objective) :: obj
      integer(int64) :: now, rate
      obj%prob = prob
      allocate (obj%replay(0))
      if (resume) then
         call read_journal(join_path(dir, journal_name), size(prob%targets), size(prob%idx), &
                           obj%replay, error)
         if (allocated(error)) return
      end if
      call obj%log%open(dir, error)
      if (allocated(error)) return
      if (size(obj%replay) > 0) call obj%log%event('resumed: replaying '// &
         str(size(obj%replay))//' evaluations from '//journal_name)
      if (present(progress)) obj%progress => progress
      call system_clock(obj%clock0, rate)
      call search(obj, outcome%opt, outcome%nstarts, error)
      call system_clock(now)
      outcome%seconds = real(now - obj%clock0, dp)/real(rate, dp)
      outcome%f_start = obj%first
      outcome%nfail = obj%nfail_total
      outcome%ninvalid = obj%ninvalid_total
      outcome%nreplayed = size(obj%replay)
      if (.not. allocated(error)) then
         outcome%opt%nevals = obj%nevals
         outcome%constants = obj%constants_of(outcome%opt%x)
         outcome%per_test = obj%best_per_test
         call obj%log%event('finished: '//outcome%opt%reason//', objective '// &
            real_str(outcome%opt%f, 'es12.5')//' after '//str(outcome%opt%nevals)//' evaluations')
      end if
      call obj%log%close()
   end subroutine run_fit
   !> The configured method from the input's start, or from each multi-start point (a Latin
   !> hypercube over the box, in log10 of the constants); the best result wins
   subroutine search(obj, opt, nstarts, error)
      type(fit_objective), intent(inout) :: obj
      type(optimum_type), intent(out) :: opt
      integer, intent(out) :: nstarts
      type(error_type), allocatable, intent(out) :: error
      type(optimum_type) :: one
      type(rng_type) :: rng
      real(dp), allocatable :: u(:, :), lo(:), hi(:), blo(:), bhi(:), x0(:)
      integer :: s, n
      associate (fc => obj%prob%cfg%fit, idx => obj%prob%idx)
         n = size(idx)
         lo = log10(fc%lower(idx))
         hi = log10(fc%upper(idx))
         blo = log10(fc%box_lower(idx))
         bhi = log10(fc%box_upper(idx))
         nstarts = max(1, fc%multistart)
         if (fc%multistart > 0) then
            call rng%seed(fc%seed)
            call latin_hypercube(rng, n, fc%multistart, u)
         end if
         do s = 1, nstarts
            if (fc%multistart > 0) then
               x0 = blo + u(:, s)*(bhi - blo)
               if (.not. fc%log_search) x0 = 10.0_dp**x0
               call obj%log%event('multi-start '//str(s)//' of '//str(nstarts)//' from evaluation '// &
                                  str(obj%nevals + 1))
            else
               x0 = obj%prob%start_point()
            end if
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
            if (allocated(error)) return
            if (s == 1 .or. one%f < opt%f) opt = one
         end do
         if (fc%multistart > 0) opt%reason = 'best of '//str(nstarts)//' starts: '//opt%reason
      end associate
   end subroutine search
end module usharp_fit
