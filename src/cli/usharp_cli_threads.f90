!> The OpenMP wait policy the program runs with. Threads that spin while they wait for work
!> take a core from whatever else runs on a shared node: with two threads on a loaded 2-core
!> machine a multi-start fit took 4 times as long spinning as with passive waiting
!> (bench/threads.sh). The policy is read once, when the OpenMP runtime loads, before any
!> Fortran code runs; so when the user has not chosen one, the program sets passive and
!> starts itself again (execv of /proc/self/exe with the same arguments).
module usharp_cli_threads
   use, intrinsic :: iso_c_binding, only: c_char, c_int, c_ptr, c_null_char, c_null_ptr, c_loc
   implicit none
   private

   public :: ensure_wait_policy

   interface
      function c_setenv(name, value, overwrite) bind(C, name='setenv') result(r)
         import :: c_char, c_int
         character(kind=c_char), intent(in) :: name(*), value(*)
         integer(c_int), value :: overwrite
         integer(c_int) :: r
      end function c_setenv
      function c_execv(path, argv) bind(C, name='execv') result(r)
         import :: c_char, c_int, c_ptr
         character(kind=c_char), intent(in) :: path(*)
         type(c_ptr), intent(in) :: argv(*)
         integer(c_int) :: r
      end function c_execv
   end interface

   !> A C string of one argument, kept alive while execv reads it
   type :: c_string
      character(kind=c_char), allocatable :: s(:)
   end type c_string

contains

   !> When OMP_WAIT_POLICY is not set: set it to passive and run the program again with the
   !> same arguments. Returns only when the variable was set already or the new start failed
   !> (the program then goes on under the runtime's default policy).
   subroutine ensure_wait_policy()
      type(c_string), allocatable, target :: args(:)
      type(c_ptr), allocatable :: argv(:)
      integer :: status, i, length
      call get_environment_variable('OMP_WAIT_POLICY', status=status)
      if (status /= 1) return
      if (c_setenv('OMP_WAIT_POLICY'//c_null_char, 'passive'//c_null_char, 1_c_int) /= 0) return
      allocate (args(0:command_argument_count()), argv(0:command_argument_count() + 1))
      do i = 0, command_argument_count()
         call get_command_argument(i, length=length)
         allocate (args(i)%s(length + 1))
         args(i)%s = to_c(i, length)
         argv(i) = c_loc(args(i)%s)
      end do
      argv(ubound(argv, 1)) = c_null_ptr
      ! execv returns only on failure
      status = c_execv('/proc/self/exe'//c_null_char, argv)
   end subroutine ensure_wait_policy

   function to_c(i, length) result(s)
      integer, intent(in) :: i, length
      character(kind=c_char) :: s(length + 1)
      character(len=length) :: arg
      integer :: k
      call get_command_argument(i, arg)
      do k = 1, length
         s(k) = arg(k:k)
      end do
      s(length + 1) = c_null_char
   end function to_c
end module usharp_cli_threads
