!> A small unit-test harness with the API of test-drive (error_type, unittest_type,
!> new_unittest, testsuite_type, new_testsuite, check, skip_test, test_failed, run_testsuite),
!> written for usharp so that moving to the real package is a manifest change.
module testdrive
   use, intrinsic :: iso_fortran_env, only: real64, error_unit
   use, intrinsic :: ieee_arithmetic, only: ieee_is_nan
   implicit none
   private

   public :: error_type, unittest_type, testsuite_type, new_unittest, new_testsuite
   public :: check, skip_test, test_failed, run_testsuite, run_unittest, test_interface
   public :: collect_interface, success, fatal, skipped

   integer, parameter :: dp = real64
   !> Outcome codes, as test-drive has them
   integer, parameter :: success = 0, fatal = 1, skipped = 77

   !> Result of a failed or skipped test
   type :: error_type
      integer :: stat = success
      character(len=:), allocatable :: message
   end type error_type

   abstract interface
      subroutine test_interface(error)
         import :: error_type
         type(error_type), allocatable, intent(out) :: error
      end subroutine test_interface
   end interface

   type :: unittest_type
      character(len=:), allocatable :: name
      procedure(test_interface), pointer, nopass :: test => null()
      logical :: should_fail = .false.
   end type unittest_type

   abstract interface
      subroutine collect_interface(testsuite)
         import :: unittest_type
         type(unittest_type), allocatable, intent(out) :: testsuite(:)
      end subroutine collect_interface
   end interface

   type :: testsuite_type
      character(len=:), allocatable :: name
      procedure(collect_interface), pointer, nopass :: collect => null()
   end type testsuite_type

   interface check
      module procedure :: check_logical
      module procedure :: check_real
      module procedure :: check_int
      module procedure :: check_string
   end interface check

contains

   function new_unittest(name, test, should_fail) result(self)
      character(len=*), intent(in) :: name
      procedure(test_interface) :: test
      logical, intent(in), optional :: should_fail
      type(unittest_type) :: self
      self%name = name
      self%test => test
      if (present(should_fail)) self%should_fail = should_fail
   end function new_unittest

   function new_testsuite(name, collect) result(self)
      character(len=*), intent(in) :: name
      procedure(collect_interface) :: collect
      type(testsuite_type) :: self
      self%name = name
      self%collect => collect
   end function new_testsuite

   !> Fail with a message unless the expression holds
   subroutine check_logical(error, expression, message, more)
      type(error_type), allocatable, intent(out) :: error
      logical, intent(in) :: expression
      character(len=*), intent(in), optional :: message, more
      if (expression) return
      call test_failed(error, opt(message, 'condition not met'), more)
   end subroutine check_logical

   !> Fail unless actual equals expected within thr (absolute, or relative with rel)
   subroutine check_real(error, actual, expected, message, more, thr, rel)
      type(error_type), allocatable, intent(out) :: error
      real(dp), intent(in) :: actual, expected
      character(len=*), intent(in), optional :: message, more
      real(dp), intent(in), optional :: thr
      logical, intent(in), optional :: rel
      real(dp) :: tol, diff
      logical :: relative
      character(len=160) :: buf
      tol = epsilon(1.0_dp)
      if (present(thr)) tol = thr
      relative = .false.
      if (present(rel)) relative = rel
      diff = abs(actual - expected)
      if (relative) diff = diff/max(abs(expected), tiny(1.0_dp))
      if (diff <= tol .and. .not. ieee_is_nan(actual)) return
      write (buf, '(a,es22.14,a,es22.14,a,es10.3)') 'expected ', expected, ' got ', actual, &
         merge(' rel. diff ', ' abs. diff ', relative), diff
      call test_failed(error, opt(message, 'values differ')//': '//trim(buf), more)
   end subroutine check_real

   subroutine check_int(error, actual, expected, message, more)
      type(error_type), allocatable, intent(out) :: error
      integer, intent(in) :: actual, expected
      character(len=*), intent(in), optional :: message, more
      character(len=80) :: buf
      if (actual == expected) return
      write (buf, '(a,i0,a,i0)') 'expected ', expected, ' got ', actual
      call test_failed(error, opt(message, 'integers differ')//': '//trim(buf), more)
   end subroutine check_int

   subroutine check_string(error, actual, expected, message, more)
      type(error_type), allocatable, intent(out) :: error
      character(len=*), intent(in) :: actual, expected
      character(len=*), intent(in), optional :: message, more
      if (actual == expected) return
      call test_failed(error, opt(message, 'strings differ')//": expected '"//expected// &
         "' got '"//actual//"'", more)
   end subroutine check_string

   subroutine test_failed(error, message, more)
      type(error_type), allocatable, intent(out) :: error
      character(len=*), intent(in) :: message
      character(len=*), intent(in), optional :: more
      allocate (error)
      error%stat = fatal
      error%message = message
      if (present(more)) error%message = error%message//' ('//more//')'
   end subroutine test_failed

   !> Mark a test as skipped, with the reason
   subroutine skip_test(error, message, more)
      type(error_type), allocatable, intent(out) :: error
      character(len=*), intent(in) :: message
      character(len=*), intent(in), optional :: more
      allocate (error)
      error%stat = skipped
      error%message = message
      if (present(more)) error%message = error%message//' ('//more//')'
   end subroutine skip_test

   pure function opt(text, default) result(res)
      character(len=*), intent(in), optional :: text
      character(len=*), intent(in) :: default
      character(len=:), allocatable :: res
      if (present(text)) then
         res = text
      else
         res = default
      end if
   end function opt

   !> Run one test, print its outcome; stat is incremented on failure
   subroutine run_unittest(test, unit, stat)
      type(unittest_type), intent(in) :: test
      integer, intent(in) :: unit
      integer, intent(inout) :: stat
      type(error_type), allocatable :: error
      call test%test(error)
      if (.not. allocated(error)) then
         if (test%should_fail) then
            write (unit, '(2x,a)') 'FAIL  '//test%name//': expected to fail'
            stat = stat + 1
         else
            write (unit, '(2x,a)') 'ok    '//test%name
         end if
      else if (error%stat == skipped) then
         write (unit, '(2x,a)') 'SKIP  '//test%name//': '//error%message
      else if (test%should_fail) then
         write (unit, '(2x,a)') 'ok    '//test%name//' (failed as expected)'
      else
         write (unit, '(2x,a)') 'FAIL  '//test%name//': '//error%message
         stat = stat + 1
      end if
   end subroutine run_unittest

   !> Run every test of a suite; stat is incremented per failed test
   subroutine run_testsuite(collect, unit, stat)
      procedure(collect_interface) :: collect
      integer, intent(in) :: unit
      integer, intent(inout) :: stat
      type(unittest_type), allocatable :: tests(:)
      integer :: i
      call collect(tests)
      do i = 1, size(tests)
         call run_unittest(tests(i), unit, stat)
      end do
   end subroutine run_testsuite
end module testdrive
