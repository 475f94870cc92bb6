!> Error handling: errors travel as an allocatable error_type; only the main program prints.
module usharp_error
   implicit none
   private

   public :: error_type, fatal_error, prefix_error
   public :: stat_input, stat_usage, stat_failure, stat_io, stat_report, stat_busy

   !> A user error in an input file or its contents (exit code 1)
   integer, parameter :: stat_input = 1
   !> A command-line usage error (exit code 2)
   integer, parameter :: stat_usage = 2
   !> A simulation or fit that failed (exit code 3)
   integer, parameter :: stat_failure = 3
   !> Output could not be written (exit code 4)
   integer, parameter :: stat_io = 4
   !> A fit that finished and whose results are written, but whose identifiability report
   !> failed (exit code 5)
   integer, parameter :: stat_report = 5
   !> The output folder is in use by another run (exit code 6)
   integer, parameter :: stat_busy = 6
   ! A run stopped by a signal exits with 128 + the signal's number (143 for SIGTERM)

   !> Error carried back to the caller
   type :: error_type
      !> Category, also the process exit code
      integer :: stat = stat_input
      !> One-line message for the user
      character(len=:), allocatable :: message
   end type error_type

contains

   !> Create a new error with a message and an optional category
   pure subroutine fatal_error(error, message, stat)
      type(error_type), allocatable, intent(out) :: error
      character(len=*), intent(in) :: message
      integer, intent(in), optional :: stat
      allocate (error)
      error%message = message
      if (present(stat)) error%stat = stat
   end subroutine fatal_error

   !> Put a context prefix (file, test name, ...) in front of an existing error message
   pure subroutine prefix_error(error, prefix)
      type(error_type), intent(inout) :: error
      character(len=*), intent(in) :: prefix
      error%message = prefix//error%message
   end subroutine prefix_error
end module usharp_error
