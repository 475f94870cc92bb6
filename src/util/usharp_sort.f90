!> Ordering of small arrays (a few hundred entries: insertion sort, stable)
module usharp_sort
   use usharp_kinds, only: dp
   implicit none
   private

   public :: order_of

contains

   !> The permutation that sorts keys in ascending order; equal keys keep their order
   pure function order_of(keys) result(order)
      real(dp), intent(in) :: keys(:)
      integer :: order(size(keys))
      integer :: i, j, tmp
      order = [(i, i=1, size(keys))]
      do i = 2, size(keys)
         tmp = order(i)
         j = i - 1
         do while (j >= 1)
            if (keys(order(j)) <= keys(tmp)) exit
            order(j + 1) = order(j)
            j = j - 1
         end do
         order(j + 1) = tmp
      end do
   end function order_of
end module usharp_sort
