!> The fit's logs: the original's GUESS.TXT, FOM.TXT and SUMS.TXT (E12.5), and a journal with
!> every evaluation at full precision from which a killed run is resumed. The journal's first
!> line is the fingerprint of everything that decides the result (program version, input
!> file, constants file, data files), and a line closes each start of the search with the
!> optimum it reached, so that a resumed run takes a finished start from the journal alone.
!> fit.cache beside it keeps, in binary at full precision, the residual vectors and
!> sensitivity Jacobians of the start under way (a least-squares search's), so that a
!> resumed Levenberg-Marquardt run replays that start instead of simulating it again; each
!> start begins a new one, so that it holds one start's worth, not the whole fit's.
module usharp_fit_log
   use, intrinsic :: iso_fortran_env, only: int32
   use usharp_kinds, only: dp
   use usharp_error, only: error_type, fatal_error, stat_io, stat_input
   use usharp_optimiser, only: optimum_type
   use usharp_strings, only: str
   use usharp_filesys, only: join_path, file_exists, raw_file, read_line, remove_file
   implicit none
   private

   public :: fit_log, journal_record, cached_jacobian, read_journal, read_cache, journal_name
   public :: cache_name, start_done

   character(len=*), parameter :: journal_name = 'fit.journal'
   character(len=*), parameter :: cache_name = 'fit.cache'
   character(len=*), parameter :: rec_fmt = '(i10,1x,i2,*(1x,es25.17e3))'
   character(len=*), parameter :: fingerprint_tag = '# fingerprint'
   !> The line that closes a start: '# start-done s first last njac nevals iterations
   !> len(reason) f x : reason' (see log_start_done)
   character(len=*), parameter :: done_tag = '# start-done'
   character(len=8), parameter :: cache_magic = 'USHARPC1'
   !> Kinds of record in fit.cache
   integer(int32), parameter :: cache_residuals = 1, cache_jacobian = 2

   !> One evaluation as the journal keeps it (r: its residuals, when fit.cache has them;
   !> message: why it failed, for an evaluation made on another rank and logged here)
   type :: journal_record
      integer :: status = 0
      real(dp) :: f = 0.0_dp
      real(dp), allocatable :: per_test(:), x(:)
      real(dp), allocatable :: r(:)
      character(len=:), allocatable :: message
   end type journal_record

   !> A sensitivity Jacobian as fit.cache keeps it (x unallocated: not kept, a finished
   !> start's)
   type :: cached_jacobian
      real(dp), allocatable :: x(:), jac(:, :)
   end type cached_jacobian

   !> A start of the search that ended, as the journal closes it: its evaluations first to
   !> last, its number of sensitivity Jacobians, and the optimum it reached
   type :: start_done
      integer :: start = 0, first = 0, last = 0, njac = 0
      type(optimum_type) :: opt
   end type start_done

   !> Open log files of a fit (written through the C library: a full disk is noticed)
   type :: fit_log
      type(raw_file) :: guess, fom, sums, journal, events, cache
      character(len=:), allocatable :: dir
      integer :: m = 0, n = 0  !< residuals and fitted constants (fit.cache's header)
   contains
      procedure :: open => log_open
      procedure :: record => log_record
      procedure :: record_jacobian => log_record_jacobian
      procedure :: start_done => log_start_done
      procedure :: new_cache => log_new_cache
      procedure :: event => log_event
      procedure :: close => log_close
   end type fit_log

contains

   !> Create the logs in dir, replacing old ones (a resumed run writes its replayed records
   !> again); the journal starts with the fingerprint line, fit.cache with its header (m
   !> residuals, n fitted constants)
   subroutine log_open(self, dir, fingerprint, m, n, error)
      class(fit_log), intent(inout) :: self
      character(len=*), intent(in) :: dir, fingerprint
      integer, intent(in) :: m, n
      type(error_type), allocatable, intent(out) :: error
      self%dir = dir
      self%m = m
      self%n = n
      ! fit.cache first: a folder where it cannot be written is refused before the journal
      ! of the run to resume is replaced
      call self%new_cache(error)
      if (.not. allocated(error)) call replace_file(self%guess, dir, 'GUESS.TXT', error)
      if (.not. allocated(error)) call replace_file(self%fom, dir, 'FOM.TXT', error)
      if (.not. allocated(error)) call replace_file(self%sums, dir, 'SUMS.TXT', error)
      if (.not. allocated(error)) call replace_file(self%events, dir, 'fit.log', error)
      if (.not. allocated(error)) call replace_file(self%journal, dir, journal_name, error)
      if (.not. allocated(error)) call self%journal%put(fingerprint_tag//' '//fingerprint// &
                                                        new_line('a'), error)
   end subroutine log_open

   !> Begin fit.cache anew (its header only): at the start of each search of a multi-start
   !> fit, the residuals of the starts before are not needed again (the journal closes them)
   subroutine log_new_cache(self, error)
      class(fit_log), intent(inout) :: self
      type(error_type), allocatable, intent(out) :: error
      call self%cache%close(error)
      if (.not. allocated(error)) call replace_file(self%cache, self%dir, cache_name, error)
      if (.not. allocated(error)) call self%cache%put(cache_magic//bytes_i([self%m, self%n]), error)
   end subroutine log_new_cache

   !> Create the file name in dir for writing, an old one removed first, not truncated: ext4
   !> writes out a truncated and rewritten file when it is closed (to keep it across a
   !> crash), which for a large fit.cache costs more than writing it
   subroutine replace_file(file, dir, name, error)
      type(raw_file), intent(inout) :: file
      character(len=*), intent(in) :: dir, name
      type(error_type), allocatable, intent(out) :: error
      logical :: gone
      gone = remove_file(join_path(dir, name))
      call file%create(join_path(dir, name), error)
   end subroutine replace_file

   !> Close start s in the journal: its evaluations first to last, its njac sensitivity
   !> Jacobians and the optimum opt it reached (x in the search space, at full precision)
   subroutine log_start_done(self, s, first, last, njac, opt, error)
      class(fit_log), intent(inout) :: self
      integer, intent(in) :: s, first, last, njac
      type(optimum_type), intent(in) :: opt
      type(error_type), allocatable, intent(out) :: error
      character(len=len(done_tag) + 7*12 + 26*(1 + size(opt%x))) :: rec
      character(len=:), allocatable :: reason
      reason = ''
      if (allocated(opt%reason)) reason = opt%reason
      write (rec, '(a,7(1x,i0),*(1x,es25.17e3))') done_tag, s, first, last, njac, opt%nevals, &
         opt%iterations, len(reason), opt%f, opt%x
      call self%journal%put(trim(rec)//' : '//reason//new_line('a'), error)
   end subroutine log_start_done

   !> Log evaluation k: x (search space) goes to the journal, constants (physical) to GUESS,
   !> the residuals r (when given) to fit.cache. Every write is checked; a failure is an
   !> error naming the file.
   subroutine log_record(self, k, status, f, per_test, x, constants, error, r)
      class(fit_log), intent(inout) :: self
      integer, intent(in) :: k, status
      real(dp), intent(in) :: f, per_test(:), x(:), constants(:)
      type(error_type), allocatable, intent(out) :: error
      real(dp), intent(in), optional :: r(:)
      character(len=12*(size(constants) + size(per_test)) + 16) :: buf
      character(len=16 + 26*(1 + size(per_test) + size(x))) :: rec
      integer :: j
      buf = ''
      do j = 1, size(constants)
         write (buf(13*(j - 1) + 1:13*j), '(E12.5,a)') constants(j), new_line('a')
      end do
      call self%guess%put(buf(:13*size(constants))//'------------'//new_line('a'), error)
      if (allocated(error)) return
      write (buf, '(E12.5)') f
      call self%fom%put(trim(buf)//new_line('a'), error)
      if (allocated(error)) return
      write (buf, '(*(E12.5))') per_test
      call self%sums%put(trim(buf)//new_line('a'), error)
      if (allocated(error)) return
      if (present(r)) then
         call self%cache%put(bytes_i([cache_residuals, k]), error)
         if (.not. allocated(error)) call self%cache%put_reals(x, error)
         if (.not. allocated(error)) call self%cache%put_reals(r, error)
         if (allocated(error)) return
      end if
      ! The journal line goes last: a record in it means the evaluation is logged everywhere
      write (rec, rec_fmt) k, status, f, per_test, x
      call self%journal%put(trim(rec)//new_line('a'), error)
   end subroutine log_record

   !> Keep the i-th sensitivity Jacobian (at x) in fit.cache
   subroutine log_record_jacobian(self, i, x, jac, error)
      class(fit_log), intent(inout) :: self
      integer, intent(in) :: i
      real(dp), intent(in) :: x(:), jac(:, :)
      type(error_type), allocatable, intent(out) :: error
      call self%cache%put(bytes_i([cache_jacobian, i]), error)
      if (.not. allocated(error)) call self%cache%put_reals(x, error)
      if (.not. allocated(error)) call self%cache%put_reals(reshape(jac, [size(jac)]), error)
   end subroutine log_record_jacobian

   !> The bytes of 32-bit integers, as fit.cache keeps them
   pure function bytes_i(v) result(b)
      integer, intent(in) :: v(:)
      character(len=4*size(v)) :: b
      b = transfer(int(v, int32), b)
   end function bytes_i


   !> A line in fit.log (warnings, penalties, the summary). A failed write here is not an
   !> error of its own: the journal's next write to the same disk reports it.
   subroutine log_event(self, text)
      class(fit_log), intent(inout) :: self
      character(len=*), intent(in) :: text
      type(error_type), allocatable :: error
      if (self%events%fd < 0) return
      call self%events%put(text//new_line('a'), error)
   end subroutine log_event

   !> Close the logs; error (when given) reports the first close that failed
   subroutine log_close(self, error)
      class(fit_log), intent(inout) :: self
      type(error_type), allocatable, intent(out), optional :: error
      call close_one(self%guess)
      call close_one(self%fom)
      call close_one(self%sums)
      call close_one(self%cache)
      call close_one(self%journal)
      call close_one(self%events)
   contains
      subroutine close_one(f)
         type(raw_file), intent(inout) :: f
         type(error_type), allocatable :: e
         call f%close(e)
         if (allocated(e) .and. present(error)) then
            if (.not. allocated(error)) call move_alloc(e, error)
         end if
      end subroutine close_one
   end subroutine log_close

   !> Read the complete records of a journal (a torn last line from a kill is dropped), the
   !> starts it closes (see log_start_done; a line whose evaluations it does not hold, or torn,
   !> closes none) and its fingerprint ('' if it has none)
   subroutine read_journal(path, ntest, nx, records, starts, fingerprint, error)
      character(len=*), intent(in) :: path
      integer, intent(in) :: ntest, nx
      type(journal_record), allocatable, intent(out) :: records(:)
      type(start_done), allocatable, intent(out) :: starts(:)
      character(len=:), allocatable, intent(out) :: fingerprint
      type(error_type), allocatable, intent(out) :: error
      type(journal_record), allocatable :: grown(:)
      type(journal_record) :: rec
      type(start_done) :: done
      character(len=:), allocatable :: line
      integer :: unit, ios, k, kk, nrec
      logical :: ok
      fingerprint = ''
      nrec = 0
      allocate (starts(0))
      if (.not. file_exists(path)) then
         call fatal_error(error, path//': no journal to resume from: start the run afresh, '// &
            'without --resume (with --force over files of an earlier run there)')
         allocate (records(0))
         return
      end if
      allocate (records(16))
      open (newunit=unit, file=path, status='old', action='read')
      allocate (rec%per_test(ntest), rec%x(nx))
      k = 0
      do
         call read_line(unit, line, ios)
         if (ios /= 0) exit
         if (index(line, fingerprint_tag) == 1) then
            fingerprint = trim(adjustl(line(len(fingerprint_tag) + 1:)))
            cycle
         end if
         if (index(line, done_tag) == 1) then
            call parse_done(line(len(done_tag) + 1:), nx, done, ok)
            if (ok) ok = done%first >= 1 .and. done%first <= done%last + 1 .and. done%last == nrec
            if (ok) starts = [starts, done]
            cycle
         end if
         read (line, *, iostat=ios) kk, rec%status, rec%f, rec%per_test, rec%x
         if (ios /= 0) exit
         ! A torn line has too few fields; a complete one ends in a full number
         if (len_trim(line) < 10 + 3 + 26*(1 + ntest + nx)) exit
         k = k + 1
         if (kk /= k) then
            call fatal_error(error, path//':'//str(k)//': evaluation '//str(kk)// &
               ' out of order', stat_input)
            exit
         end if
         ! Grown by doubling: a journal of many evaluations is read in linear time
         if (nrec == size(records)) then
            allocate (grown(2*nrec))
            grown(:nrec) = records(:nrec)
            call move_alloc(grown, records)
         end if
         nrec = nrec + 1
         records(nrec) = rec
      end do
      close (unit)
      records = records(:nrec)
   contains
      !> A start-done line after its tag; ok false where it is torn (its reason is not as
      !> long as the line says) or not one
      subroutine parse_done(text, nx, done, ok)
         character(len=*), intent(in) :: text
         integer, intent(in) :: nx
         type(start_done), intent(out) :: done
         logical, intent(out) :: ok
         integer :: colon, nreason, ios
         ok = .false.
         colon = index(text, ' : ')
         if (colon == 0) return
         allocate (done%opt%x(nx))
         read (text(:colon - 1), *, iostat=ios) done%start, done%first, done%last, done%njac, &
            done%opt%nevals, done%opt%iterations, nreason, done%opt%f, done%opt%x
         if (ios /= 0) return
         done%opt%reason = text(colon + 3:)
         ok = len(done%opt%reason) == nreason
      end subroutine parse_done
   end subroutine read_journal


   !> Attach the residuals kept in fit.cache to the journal's records (where the cache has
   !> them at the record's point, and their squares sum to the record's objective: damaged
   !> bytes would steer the search off the journal) and return its sensitivity Jacobians. A
   !> missing, foreign, torn or damaged cache only means less is replayed.
   subroutine read_cache(path, m, records, jacobians)
      character(len=*), intent(in) :: path
      integer, intent(in) :: m
      type(journal_record), intent(inout) :: records(:)
      type(cached_jacobian), allocatable, intent(out) :: jacobians(:)
      character(len=8) :: magic
      integer(int32) :: mm, nn, kind, k
      real(dp), allocatable :: x(:), r(:), jac(:, :)
      integer :: unit, ios, n
      allocate (jacobians(0))
      if (size(records) == 0) return
      n = size(records(1)%x)
      open (newunit=unit, file=path, status='old', action='read', access='stream', &
            form='unformatted', iostat=ios)
      if (ios /= 0) return
      read (unit, iostat=ios) magic, mm, nn
      if (ios /= 0 .or. magic /= cache_magic .or. mm /= m .or. nn /= n) then
         close (unit)
         return
      end if
      allocate (x(n), r(m), jac(m, n))
      do
         read (unit, iostat=ios) kind, k
         if (ios /= 0) exit
         select case (kind)
         case (cache_residuals)
            read (unit, iostat=ios) x, r
            if (ios /= 0) exit
            if (k < 1 .or. k > size(records)) cycle
            if (all(x == records(k)%x) .and. agrees(r, records(k)%f)) records(k)%r = r
         case (cache_jacobian)
            read (unit, iostat=ios) x, jac
            if (ios /= 0) exit
            ! Jacobian k at index k: the cache begins with the start under way, whose first
            ! Jacobian need not be the fit's first. Each is taken at an evaluated point, so
            ! a number beyond the evaluations is damage, not a Jacobian
            if (k <= size(jacobians) .or. k > size(records) + 1) exit
            if (k > size(jacobians) + 1) call grow_jacobians(jacobians, k - 1)
            jacobians = [jacobians, cached_jacobian(x, jac)]
         case default
            exit
         end select
      end do
      close (unit)
   contains
      !> jacobians grown to n entries with empty ones (not kept)
      subroutine grow_jacobians(jacobians, n)
         type(cached_jacobian), allocatable, intent(inout) :: jacobians(:)
         integer, intent(in) :: n
         type(cached_jacobian), allocatable :: grown(:)
         allocate (grown(n))
         grown(:size(jacobians)) = jacobians
         call move_alloc(grown, jacobians)
      end subroutine grow_jacobians
      !> Whether residuals r give the objective f (a failed evaluation's are all 0, its f a
      !> penalty); the journal keeps f to 17 digits, the sum's order may differ
      pure logical function agrees(r, f)
         real(dp), intent(in) :: r(:), f
         agrees = all(r == 0.0_dp)
         if (.not. agrees) agrees = abs(sum(r**2) - f) <= 1.0e-10_dp*abs(f)
      end function agrees
   end subroutine read_cache

end module usharp_fit_log
