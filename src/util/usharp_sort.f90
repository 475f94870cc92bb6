!> Ordering of small arrays (a few hundred entries: insertion sort, stable) and the median
module usharp_sort
   use usharp_kinds, only: dp
   implicit none
   private

   public :: order_of, median

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

   !> Median (selection by partial sorting of a copy)
   pure real(dp) function median(a) result(med)
      real(dp), intent(in) :: a(:)
      real(dp) :: b(size(a)), pivot, tmp
      integer :: lo, hi, i, j, k
      b = a
      k = (size(b) + 1)/2
      lo = 1
      hi = size(b)
      do while (lo < hi)
         pivot = b((lo + hi)/2)
         i = lo
         j = hi
         do while (i <= j)
            do while (b(i) < pivot)
               i = i + 1
            end do
            do while (b(j) > pivot)
               j = j - 1
            end do
            if (i <= j) then
               tmp = b(i); b(i) = b(j); b(j) = tmp
               i = i + 1
               j = j - 1
            end if
         end do
         if (k <= j) then
            hi = j
         else if (k >= i) then
            lo = i
         else
            exit
         end if
      end do
      med = b(k)
   end function median
end module usharp_sort
