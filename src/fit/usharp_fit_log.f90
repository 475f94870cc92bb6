!> The fit's logs: the original's GUESS.TXT, FOM.TXT and SUMS.TXT (E12.5), and a journal with
!> every evaluation at full precision from which a killed run is resumed
module usharp_fit_log
   use usharp_kinds, only: dp
   use usharp_error, only: error_type, fatal_error, stat_io, stat_input
   use usharp_strings, only: str
   use usharp_filesys, only: join_path, file_exists
   implicit none
   private

   public :: fit_log, journal_record, read_journal, journal_name

   character(len=*), parameter :: journal_name = 'fit.journal'
   character(len=*), parameter :: rec_fmt = '(i10,1x,i2,*(1x,es25.17e3))'

   !> One evaluation as the journal keeps it
   type :: journal_record
      integer :: status = 0
      real(dp) :: f = 0.0_dp
      real(dp), allocatable :: per_test(:), x(:)
   end type journal_record

   !> Open log files of a fit
   type :: fit_log
      integer :: guess = -1, fom = -1, sums = -1, journal = -1, events = -1
   contains
      procedure :: open => log_open
      procedure :: record => log_record
      procedure :: event => log_event
      procedure :: close => log_close
   end type fit_log

contains

   !> Create the logs in dir, replacing old ones (a resumed run writes its replayed records again)
   subroutine log_open(self, dir, error)
      class(fit_log), intent(inout) :: self
      character(len=*), intent(in) :: dir
      type(error_type), allocatable, intent(out) :: error
      call open_one(self%guess, 'GUESS.TXT')
      call open_one(self%fom, 'FOM.TXT')
      call open_one(self%sums, 'SUMS.TXT')
      call open_one(self%events, 'fit.log')
      call open_one(self%journal, journal_name)
   contains
      subroutine open_one(unit, name)
         integer, intent(out) :: unit
         character(len=*), intent(in) :: name
         integer :: ios
         character(len=256) :: msg
         if (allocated(error)) return
         open (newunit=unit, file=join_path(dir, name), status='replace', action='write', &
               iostat=ios, iomsg=msg)
         if (ios /= 0) call fatal_error(error, join_path(dir, name)//': cannot write ('// &
            trim(msg)//')', stat_io)
      end subroutine open_one
   end subroutine log_open

   !> Log evaluation k: x (search space) goes to the journal, constants (physical) to GUESS
   subroutine log_record(self, k, status, f, per_test, x, constants)
      class(fit_log), intent(inout) :: self
      integer, intent(in) :: k, status
      real(dp), intent(in) :: f, per_test(:), x(:), constants(:)
      integer :: j
      do j = 1, size(constants)
         write (self%guess, '(E12.5)') constants(j)
      end do
      write (self%guess, '(a)') '------------'
      write (self%fom, '(E12.5)') f
      write (self%sums, '(*(E12.5))') per_test
      ! The journal line goes last: a record in it means the evaluation is logged everywhere
      write (self%journal, rec_fmt) k, status, f, per_test, x
      flush (self%guess)
      flush (self%fom)
      flush (self%sums)
      flush (self%journal)
   end subroutine log_record

   !> A line in fit.log (warnings, penalties, the summary)
   subroutine log_event(self, text)
      class(fit_log), intent(inout) :: self
      character(len=*), intent(in) :: text
      write (self%events, '(a)') text
      flush (self%events)
   end subroutine log_event

   subroutine log_close(self)
      class(fit_log), intent(inout) :: self
      if (self%guess >= 0) close (self%guess)
      if (self%fom >= 0) close (self%fom)
      if (self%sums >= 0) close (self%sums)
      if (self%journal >= 0) close (self%journal)
      if (self%events >= 0) close (self%events)
   end subroutine log_close

   !> Read the complete records of a journal (a torn last line from a kill is dropped)
   subroutine read_journal(path, ntest, nx, records, error)
      character(len=*), intent(in) :: path
      integer, intent(in) :: ntest, nx
      type(journal_record), allocatable, intent(out) :: records(:)
      type(error_type), allocatable, intent(out) :: error
      type(journal_record) :: rec
      character(len=4096) :: line
      integer :: unit, ios, k, kk
      allocate (records(0))
      if (.not. file_exists(path)) then
         call fatal_error(error, path//': no journal to resume from (run without --resume first)')
         return
      end if
      open (newunit=unit, file=path, status='old', action='read')
      allocate (rec%per_test(ntest), rec%x(nx))
      k = 0
      do
         read (unit, '(a)', iostat=ios) line
         if (ios /= 0) exit
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
         records = [records, rec]
      end do
      close (unit)
   end subroutine read_journal
end module usharp_fit_log
