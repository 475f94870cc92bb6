!> The journal of a diagnosis, so that one stopped by a signal (a cluster job at its wall
!> time) continues with --resume: its expensive deterministic units (each optimisation, each
!> set of starts) are numbered in the fixed order the diagnosis runs them, and each one's
!> outcome is kept at full precision (the bits of every real) in a usharp_journal file. On
!> resume the units found there are replayed instead of computed, so that the diagnosis
!> takes the same path to the same numbers on any number of ranks. Each unit carries the
!> digest of what it computed (its problem, start points and settings), and a unit is
!> replayed only for the same request: a journal that another build of usharp wrote, whose
!> units come in another order or start elsewhere, is refused where it parts from this run
!> rather than misread. A stop signal is looked at before each unit computed (over all
!> ranks, which run the units in the same order).
module usharp_diagnose_journal
   use, intrinsic :: iso_fortran_env, only: int64
   use usharp_kinds, only: dp
   use usharp_error, only: error_type, fatal_error, stat_input
   use usharp_filesys, only: hash_text, hash_hex
   use usharp_strings, only: str
   use usharp_journal, only: journal_file
   use usharp_optimiser, only: optimum_type
   use usharp_signal, only: catch_stop_signals, release_stop_signals, stop_signal
   use usharp_mpi, only: any_rank
   implicit none
   private

   public :: diagnose_journal, next_unit, record_unit, unit_stopped, unit_digest
   public :: optimum_text, read_optimum, reals_text, read_reals, text_lines

   !> A diagnosis's open journal and the units taken so far
   type :: diagnose_journal
      type(journal_file) :: file
      integer :: next = 0          !< units taken (replayed or computed)
      integer :: stopped = 0       !< the stop signal that ended it (0: none)
   contains
      procedure :: open => dj_open
      procedure :: close => dj_close
   end type diagnose_journal

   !> The first line of a unit's text, before its request's digest
   character(len=*), parameter :: unit_tag = 'request '

contains

   !> Open the journal at path (mode and fingerprint: see journal_file's open) and catch the
   !> stop signals from now on
   subroutine dj_open(self, path, fingerprint, mode, error)
      class(diagnose_journal), intent(inout) :: self
      character(len=*), intent(in) :: path, fingerprint, mode
      type(error_type), allocatable, intent(out) :: error
      self%next = 0
      self%stopped = 0
      call self%file%open(path, fingerprint, mode, error)
      if (.not. allocated(error)) call catch_stop_signals()
   end subroutine dj_open

   !> Close it (error: the close failed); the stop signals end the process again
   subroutine dj_close(self, error)
      class(diagnose_journal), intent(inout) :: self
      type(error_type), allocatable, intent(out) :: error
      call release_stop_signals()
      call self%file%close(error)
   end subroutine dj_close

   !> The digest of a unit's request (what it computes, as text), as its journal keeps it
   pure function unit_digest(request) result(digest)
      character(len=*), intent(in) :: request
      character(len=16) :: digest
      digest = hash_hex(hash_text(request))
   end function unit_digest

   !> Take the next unit, whose request has this digest (see unit_digest): replay is true with
   !> its text when the journal holds it, else it is to be computed, unless a stop signal has
   !> come (to any rank): then error says to continue with --resume. A unit the journal holds
   !> for another request is an error. Without a journal (null) every unit is computed.
   subroutine next_unit(jr, digest, text, replay, error)
      type(diagnose_journal), pointer, intent(in) :: jr
      character(len=*), intent(in) :: digest
      character(len=:), allocatable, intent(out) :: text
      logical, intent(out) :: replay
      type(error_type), allocatable, intent(out) :: error
      integer :: eol
      replay = .false.
      if (.not. associated(jr)) return
      jr%next = jr%next + 1
      if (jr%next <= size(jr%file%done)) then
         text = jr%file%done(jr%next)%s
         eol = index(text, new_line('a'))
         if (eol == 0 .or. text(:max(eol - 1, 0)) /= unit_tag//digest) then
            call fatal_error(error, jr%file%path//': cannot resume: its unit '//str(jr%next)// &
               ' was made for another computation than this run asks for there (a journal '// &
               'written by another build of usharp, or altered); start again with --force', stat_input)
            return
         end if
         text = text(eol + 1:)
         replay = .true.
         return
      end if
      ! Once stopped, every later unit says so (without asking the other ranks again)
      if (jr%stopped == 0) then
         ! (a rank the signal did not reach says SIGTERM, what a launcher passes on)
         if (any_rank(stop_signal() /= 0)) jr%stopped = merge(stop_signal(), 15, stop_signal() /= 0)
      end if
      if (jr%stopped /= 0) call fatal_error(error, 'stopped by a signal after '//str(jr%next - 1)// &
         ' units of the diagnosis; continue with --resume', 128 + jr%stopped)
   end subroutine next_unit

   !> The outcome of the unit just computed, with its request's digest (as given to
   !> next_unit), into the journal (rank 0 writes it)
   subroutine record_unit(jr, digest, text, error)
      type(diagnose_journal), pointer, intent(in) :: jr
      character(len=*), intent(in) :: digest, text
      type(error_type), allocatable, intent(out) :: error
      if (.not. associated(jr)) return
      call jr%file%put(jr%next, unit_tag//digest//new_line('a')//text, error)
   end subroutine record_unit

   !> Whether a stop signal has ended the diagnosis (its later units are not computed)
   logical function unit_stopped(jr)
      type(diagnose_journal), pointer, intent(in) :: jr
      unit_stopped = .false.
      if (associated(jr)) unit_stopped = jr%stopped /= 0
   end function unit_stopped

   !> An optimum and the error that came with it, as lines: 'stat nevals iterations has_x
   !> nx', the objective and x (bits), the reason, the error's message
   function optimum_text(opt, error) result(text)
      type(optimum_type), intent(in) :: opt
      type(error_type), allocatable, intent(in) :: error
      character(len=:), allocatable :: text
      character(len=:), allocatable :: reason, message
      integer :: stat, nx
      stat = 0
      message = ''
      if (allocated(error)) then
         stat = error%stat
         message = error%message
      end if
      nx = 0
      if (allocated(opt%x)) nx = size(opt%x)
      reason = ''
      if (allocated(opt%reason)) reason = opt%reason
      text = str(stat)//' '//str(opt%nevals)//' '//str(opt%iterations)//' '// &
             str(merge(1, 0, allocated(opt%x)))//' '//str(nx)//new_line('a')// &
             reals_text([opt%f])
      if (allocated(opt%x)) text = text//reals_text(opt%x)
      text = text//'reason '//reason//new_line('a')//'error '//message//new_line('a')
   end function optimum_text

   !> The optimum and error of optimum_text's lines from line `at` on (at: past them)
   subroutine read_optimum(lines, at, opt, error)
      character(len=*), intent(in) :: lines(:)
      integer, intent(inout) :: at
      type(optimum_type), intent(out) :: opt
      type(error_type), allocatable, intent(out) :: error
      integer :: stat, has_x, nx
      real(dp), allocatable :: f(:)
      read (lines(at), *) stat, opt%nevals, opt%iterations, has_x, nx
      at = at + 1
      call read_reals(lines, at, 1, f)
      opt%f = f(1)
      if (has_x == 1) call read_reals(lines, at, nx, opt%x)
      opt%reason = trim(lines(at)(len('reason ') + 1:))
      at = at + 1
      if (stat /= 0) call fatal_error(error, trim(lines(at)(len('error ') + 1:)), stat)
      at = at + 1
   end subroutine read_optimum

   !> Reals as lines of their bits (hexadecimal), 4 a line: read back exactly
   pure function reals_text(x) result(text)
      real(dp), intent(in) :: x(:)
      character(len=:), allocatable :: text
      character(len=16) :: hex
      integer :: j
      text = ''
      do j = 1, size(x)
         write (hex, '(z16.16)') transfer(x(j), 0_int64)
         text = text//hex
         if (mod(j, 4) == 0 .or. j == size(x)) then
            text = text//new_line('a')
         else
            text = text//' '
         end if
      end do
   end function reals_text

   !> n reals of reals_text's lines from line `at` on (at: past them)
   subroutine read_reals(lines, at, n, x)
      character(len=*), intent(in) :: lines(:)
      integer, intent(inout) :: at
      integer, intent(in) :: n
      real(dp), allocatable, intent(out) :: x(:)
      integer(int64) :: bits
      integer :: j, c
      allocate (x(n))
      do j = 1, n
         c = mod(j - 1, 4)
         read (lines(at)(17*c + 1:17*c + 16), '(z16)') bits
         x(j) = transfer(bits, 1.0_dp)
         if (c == 3 .or. j == n) at = at + 1
      end do
   end subroutine read_reals

   !> The lines of text (each ended by new_line('a')), blank-padded to the longest
   pure function text_lines(text) result(lines)
      character(len=*), intent(in) :: text
      character(len=:), allocatable :: lines(:)
      integer :: i, i0, n, longest
      n = 0
      longest = 0
      i0 = 1
      do i = 1, len(text)
         if (text(i:i) /= new_line('a')) cycle
         n = n + 1
         longest = max(longest, i - i0)
         i0 = i + 1
      end do
      allocate (character(len=longest) :: lines(n))
      n = 0
      i0 = 1
      do i = 1, len(text)
         if (text(i:i) /= new_line('a')) cycle
         n = n + 1
         lines(n) = text(i0:i - 1)
         i0 = i + 1
      end do
   end function text_lines
end module usharp_diagnose_journal
