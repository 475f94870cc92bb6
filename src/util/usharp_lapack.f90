!> Explicit interfaces to the LAPACK routines usharp calls
module usharp_lapack
   use usharp_kinds, only: dp
   implicit none
   private

   public :: dgesv, solve_dense

   interface
      !> Solve A X = B by LU factorisation with partial pivoting (LAPACK)
      pure subroutine dgesv(n, nrhs, a, lda, ipiv, b, ldb, info)
         import :: dp
         integer, intent(in) :: n, nrhs, lda, ldb
         real(dp), intent(inout) :: a(lda, *)
         integer, intent(out) :: ipiv(*)
         real(dp), intent(inout) :: b(ldb, *)
         integer, intent(out) :: info
      end subroutine dgesv
   end interface

contains

   !> Solve a x = b for several right-hand sides (b is overwritten by x); info /= 0 if singular
   pure subroutine solve_dense(a, b, info)
      real(dp), intent(in) :: a(:, :)
      real(dp), intent(inout) :: b(:, :)
      integer, intent(out) :: info
      real(dp) :: lu(size(a, 1), size(a, 2)), x(size(b, 1), size(b, 2))
      integer :: ipiv(size(a, 1))
      ! Contiguous copies: callers may pass array sections
      lu = a
      x = b
      call dgesv(size(a, 1), size(b, 2), lu, size(a, 1), ipiv, x, size(x, 1), info)
      b = x
   end subroutine solve_dense
end module usharp_lapack
