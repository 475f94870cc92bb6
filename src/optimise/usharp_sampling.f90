!> Space-filling samples for multi-start
module usharp_sampling
   use usharp_kinds, only: dp
   use usharp_rng, only: rng_type
   implicit none
   private

   public :: latin_hypercube

contains

   !> m points of a Latin hypercube in (0, 1)**n: in every coordinate each of the m strata
   !> holds exactly one point, at a random place inside it; strata paired at random
   subroutine latin_hypercube(rng, n, m, u)
      type(rng_type), intent(inout) :: rng
      integer, intent(in) :: n, m
      real(dp), allocatable, intent(out) :: u(:, :)
      integer :: perm(m), i, j, k, tmp
      allocate (u(n, m))
      do i = 1, n
         perm = [(j, j=1, m)]
         ! Fisher-Yates shuffle
         do j = m, 2, -1
            k = 1 + min(j - 1, int(rng%uniform()*real(j, dp)))
            tmp = perm(j)
            perm(j) = perm(k)
            perm(k) = tmp
         end do
         do j = 1, m
            u(i, j) = (real(perm(j) - 1, dp) + rng%uniform())/real(m, dp)
         end do
      end do
   end subroutine latin_hypercube
end module usharp_sampling
