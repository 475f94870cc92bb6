!> The interface every optimiser minimises through
module usharp_optimiser
   use usharp_kinds, only: dp
   use usharp_error, only: error_type
   implicit none
   private

   public :: objective_type, optimum_type

   !> A scalar objective of a parameter vector. An error stops the optimiser at once.
   type, abstract :: objective_type
   contains
      procedure(eval_interface), deferred :: eval
   end type objective_type

   abstract interface
      subroutine eval_interface(self, x, f, error)
         import :: objective_type, dp, error_type
         class(objective_type), intent(inout) :: self
         real(dp), intent(in) :: x(:)
         real(dp), intent(out) :: f
         type(error_type), allocatable, intent(out) :: error
      end subroutine eval_interface
   end interface

   !> What an optimiser returns
   type :: optimum_type
      real(dp), allocatable :: x(:)
      real(dp) :: f = huge(1.0_dp)
      integer :: nevals = 0
      integer :: iterations = 0
      character(len=:), allocatable :: reason  !< why it stopped
   end type optimum_type
end module usharp_optimiser
