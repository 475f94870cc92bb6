!> Helpers for the tests: scratch files and locating the usharp executable
module test_util
   use testdrive, only: error_type, test_failed, skip_test
   use usharp_error, only: uerror => error_type
   use usharp_filesys, only: make_dir
   implicit none
   private
   public :: scratch_dir, write_text, usharp_exe, require_exe, read_text, check_message, fit_deck

   !> Scratch folder for test files (inside the build tree, never in the sources)
   character(len=*), parameter :: scratch_dir = 'build/test-scratch'

contains

   !> Fail unless the usharp error e exists and its message contains text
   subroutine check_message(error, e, text)
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable, intent(in) :: e
      character(len=*), intent(in) :: text
      if (.not. allocated(e)) then
         call test_failed(error, 'no error for: '//text)
      else if (index(e%message, text) == 0) then
         call test_failed(error, "message '"//e%message//"' lacks '"//text//"'")
      end if
   end subroutine check_message

   !> Write lines of text to scratch_dir/name and return the path
   function write_text(name, lines) result(path)
      character(len=*), intent(in) :: name
      character(len=*), intent(in) :: lines(:)
      character(len=:), allocatable :: path
      type(uerror), allocatable :: uerr
      integer :: unit, i
      call make_dir(scratch_dir, uerr)
      path = scratch_dir//'/'//name
      open (newunit=unit, file=path, status='replace', action='write')
      do i = 1, size(lines)
         write (unit, '(a)') trim(lines(i))
      end do
      close (unit)
   end function write_text

   !> A thesis-units fit deck in scratch_dir/name fitting H1 and n from Table 4's constants
   !> with Hooke-Jeeves, then test_lines; extra_fit: further &fit settings (rho and eps given
   !> there replace the deck's, since a variable given twice is an input error)
   function fit_deck(name, extra_fit, test_lines) result(path)
      character(len=*), intent(in) :: name, extra_fit
      character(len=*), intent(in) :: test_lines(:)
      character(len=:), allocatable :: path, fit
      character(len=:), allocatable :: lines(:)
      fit = "&fit fitted='H1','n'"
      if (len_trim(extra_fit) > 0) fit = fit//', '//extra_fit
      if (index(extra_fit, 'rho=') == 0) fit = fit//', rho=0.5'
      if (index(extra_fit, 'eps=') == 0) fit = fit//', eps=1e-4'
      fit = fit//', itermax=200 /'
      allocate (character(len=max(100, len(fit), len(test_lines))) :: lines(3 + size(test_lines)))
      lines(1) = "&model name='miller', units='ksi', temperature=866.15, tm=1800.0, youngs=22.5e3 /"
      lines(2) = '&constants a1=0.8, a2=7.42e-5, b=1e15, c2=0.1, h1=200, h2=100, n=5.0, q=91000 /'
      lines(3) = fit
      lines(4:) = test_lines
      path = write_text(name, lines)
   end function fit_deck

   !> Whole text of a file (lines joined by new lines), '' if missing
   function read_text(path) result(text)
      character(len=*), intent(in) :: path
      character(len=:), allocatable :: text
      character(len=4096) :: line
      integer :: unit, ios
      text = ''
      open (newunit=unit, file=path, status='old', action='read', iostat=ios)
      if (ios /= 0) return
      do
         read (unit, '(a)', iostat=ios) line
         if (ios /= 0) exit
         text = text//trim(line)//new_line('a')
      end do
      close (unit)
   end function read_text

   !> Path of the usharp executable that fpm built next to this test program ('' if absent):
   !> build/<compiler_hash>/test/tester -> build/<compiler_hash>/app/usharp
   function usharp_exe() result(path)
      character(len=:), allocatable :: path
      character(len=1024) :: self
      integer :: k
      logical :: exists
      call get_command_argument(0, self)
      k = index(self, '/test/', back=.true.)
      path = ''
      if (k == 0) return
      path = self(:k)//'app/usharp'
      inquire (file=path, exist=exists)
      if (.not. exists) path = ''
   end function usharp_exe

   !> The usharp executable next to this test program; when it is missing the test is
   !> skipped (error set) with the reason
   subroutine require_exe(exe, error)
      character(len=:), allocatable, intent(out) :: exe
      type(error_type), allocatable, intent(out) :: error
      exe = usharp_exe()
      if (len(exe) == 0) call skip_test(error, 'usharp executable not found next to the tester')
   end subroutine require_exe
end module test_util
