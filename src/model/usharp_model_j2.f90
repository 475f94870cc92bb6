!> Tools the 3-D J2 stress updates of the models share: Mandel vectors (11, 22, 33,
!> sqrt2*12, sqrt2*23, sqrt2*13, so that double contractions are dot products), the
!> deviatoric projector and a small dense solver.
!> The local systems are solved in place rather than through LAPACK, so that a drop-in user
!> material links into an FE code without a LAPACK library.
module usharp_model_j2
   use usharp_kinds, only: dp
   implicit none
   private

   public :: deviator_projector, solve_dense, m_vec

   !> The second-order identity in Mandel form
   real(dp), parameter :: m_vec(6) = [1.0_dp, 1.0_dp, 1.0_dp, 0.0_dp, 0.0_dp, 0.0_dp]

contains

   !> Deviatoric projector in Mandel form
   pure function deviator_projector() result(p)
      real(dp) :: p(6, 6)
      integer :: i
      p = -spread(m_vec, 1, 6)*spread(m_vec, 2, 6)/3.0_dp
      do i = 1, 6
         p(i, i) = p(i, i) + 1.0_dp
      end do
   end function deviator_projector

   !> Solve a x = b (b overwritten by x) by Gaussian elimination with partial pivoting;
   !> info = 1 when a pivot is zero (a singular matrix)
   pure subroutine solve_dense(a, b, info)
      real(dp), intent(in) :: a(:, :)
      real(dp), intent(inout) :: b(:, :)
      integer, intent(out) :: info
      real(dp) :: lu(size(a, 1), size(a, 2)), row(size(a, 2)), rhs(size(b, 2)), f
      integer :: n, i, k, piv
      n = size(a, 1)
      lu = a
      info = 1
      do k = 1, n
         piv = k - 1 + maxloc(abs(lu(k:n, k)), 1)
         if (.not. abs(lu(piv, k)) > 0.0_dp) return  ! also a NaN
         if (piv /= k) then
            row = lu(k, :)
            lu(k, :) = lu(piv, :)
            lu(piv, :) = row
            rhs = b(k, :)
            b(k, :) = b(piv, :)
            b(piv, :) = rhs
         end if
         do i = k + 1, n
            f = lu(i, k)/lu(k, k)
            lu(i, k + 1:n) = lu(i, k + 1:n) - f*lu(k, k + 1:n)
            b(i, :) = b(i, :) - f*b(k, :)
         end do
      end do
      do k = n, 1, -1
         b(k, :) = (b(k, :) - matmul(lu(k, k + 1:n), b(k + 1:n, :)))/lu(k, k)
      end do
      info = 0
   end subroutine solve_dense
end module usharp_model_j2
