!> The fit's logs: the original's GUESS.TXT, FOM.TXT and SUMS.TXT (E12.5), and a journal with
!> every evaluation at full precision from which a killed run is resumed. The journal's first
!> line is the fingerprint of everything that decides the result (program version, input
!> file, constants file, data files); fit.cache beside it keeps, in binary at full precision,
!> the residual vectors and sensitivity Jacobians a least-squares fit computed, so that a
!> resumed Levenberg-Marquardt run replays them instead of simulating again.
module usharp_fit_log
   use, intrinsic :: iso_fortran_env, only: int32
   use usharp_kinds, only: dp
   use usharp_error, only: error_type, fatal_error, stat_io, stat_input
   use usharp_strings, only: str
   use usharp_filesys, only: join_path, file_exists, raw_file, read_line, remove_file
   implicit none
   private

   public :: fit_log, journal_record, cached_jacobian, read_journal, read_cache, journal_name
   public :: cache_name

   character(len=*), parameter :: journal_name = 'fit.journal'
   character(len=*), parameter :: cache_name = 'fit.cache'
   character(len=*), parameter :: rec_fmt = '(i10,1x,i2,*(1x,es25.17e3))'
   character(len=*), parameter :: fingerprint_tag = '# fingerprint'
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

   !> A sensitivity Jacobian as fit.cache keeps it
   type :: cached_jacobian
      real(dp), allocatable :: x(:), jac(:, :)
   end type cached_jacobian

   !> Open log files of a fit (written through the C library: a full disk is noticed)
   type :: fit_log
      type(raw_file) :: guess, fom, sums, journal, events, cache
      character(len=:), allocatable :: dir
   contains
      procedure :: open => log_open
      procedure :: record => log_record
      procedure :: record_jacobian => log_record_jacobian
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
      call replace(self%guess, 'GUESS.TXT')
      if (.not. allocated(error)) call replace(self%fom, 'FOM.TXT')
      if (.not. allocated(error)) call replace(self%sums, 'SUMS.TXT')
      if (.not. allocated(error)) call replace(self%events, 'fit.log')
      if (.not. allocated(error)) call replace(self%journal, journal_name)
      if (.not. allocated(error)) call replace(self%cache, cache_name)
      if (.not. allocated(error)) call self%journal%put(fingerprint_tag//' '//fingerprint// &
                                                        new_line('a'), error)
      if (.not. allocated(error)) call self%cache%put(cache_magic//bytes_i([m, n]), error)
   contains
      !> The old file is removed, not truncated: ext4 writes out a truncated and rewritten
      !> file when it is closed (to keep it across a crash), which for fit.cache's hundreds
      !> of megabytes costs more than writing them
      subroutine replace(file, name)
         type(raw_file), intent(inout) :: file
         character(len=*), intent(in) :: name
         logical :: gone
         gone = remove_file(join_path(dir, name))
         call file%create(join_path(dir, name), error)
      end subroutine replace
   end subroutine log_open

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

   !> Read the complete records of a journal (a torn last line from a kill is dropped) and
   !> its fingerprint ('' if it has none)
   subroutine read_journal(path, ntest, nx, records, fingerprint, error)
      character(len=*), intent(in) :: path
      integer, intent(in) :: ntest, nx
      type(journal_record), allocatable, intent(out) :: records(:)
      character(len=:), allocatable, intent(out) :: fingerprint
      type(error_type), allocatable, intent(out) :: error
      type(journal_record), allocatable :: grown(:)
      type(journal_record) :: rec
      character(len=:), allocatable :: line
      integer :: unit, ios, k, kk, nrec
      fingerprint = ''
      nrec = 0
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
            if (k /= size(jacobians) + 1) exit
            jacobians = [jacobians, cached_jacobian(x, jac)]
         case default
            exit
         end select
      end do
      close (unit)
   contains
      !> Whether residuals r give the objective f (a failed evaluation's are all 0, its f a
      !> penalty); the journal keeps f to 17 digits, the sum's order may differ
      pure logical function agrees(r, f)
         real(dp), intent(in) :: r(:), f
         agrees = all(r == 0.0_dp)
         if (.not. agrees) agrees = abs(sum(r**2) - f) <= 1.0e-10_dp*abs(f)
      end function agrees
   end subroutine read_cache

end module usharp_fit_log
