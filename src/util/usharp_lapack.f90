!> Explicit interfaces to the LAPACK routines usharp calls
module usharp_lapack
   use usharp_kinds, only: dp
   use usharp_math, only: log_dp
   implicit none
   private

   public :: dgesv, solve_dense, dgesvd, svd, dpotrf, logdet_spd, mat_mul

   !> Matrix products in one fixed order of operations: the same bits on every processor.
   !> gfortran's library matmul (called for large arrays) picks a kernel by the processor's
   !> features (AVX, AVX2 with fused multiply-add, AVX-512): a Jacobian's J'J then differed in
   !> the last bit from processor to processor, and a multi-start fit took another path
   !> (the quick start: 1866 evaluations natively, 1358 without AVX-512, under valgrind)
   interface mat_mul
      module procedure mat_mul_mm, mat_mul_mv
   end interface mat_mul

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
      !> Singular value decomposition A = U S V' (LAPACK)
      pure subroutine dgesvd(jobu, jobvt, m, n, a, lda, s, u, ldu, vt, ldvt, work, lwork, info)
         import :: dp
         character, intent(in) :: jobu, jobvt
         integer, intent(in) :: m, n, lda, ldu, ldvt, lwork
         real(dp), intent(inout) :: a(lda, *)
         real(dp), intent(out) :: s(*), u(ldu, *), vt(ldvt, *), work(*)
         integer, intent(out) :: info
      end subroutine dgesvd
      !> Cholesky factorisation of a symmetric positive definite matrix (LAPACK)
      pure subroutine dpotrf(uplo, n, a, lda, info)
         import :: dp
         character, intent(in) :: uplo
         integer, intent(in) :: n, lda
         real(dp), intent(inout) :: a(lda, *)
         integer, intent(out) :: info
      end subroutine dpotrf
   end interface

contains

   !> Singular values s (descending) and right singular vectors (columns of v) of a (m >= n)
   pure subroutine svd(a, s, v, info)
      real(dp), intent(in) :: a(:, :)
      real(dp), intent(out) :: s(:), v(:, :)
      integer, intent(out) :: info
      real(dp) :: acopy(size(a, 1), size(a, 2)), u(1, 1), vt(size(a, 2), size(a, 2)), q(1)
      real(dp), allocatable :: work(:)
      integer :: m, n
      m = size(a, 1)
      n = size(a, 2)
      acopy = a
      call dgesvd('N', 'A', m, n, acopy, m, s, u, 1, vt, n, q, -1, info)
      allocate (work(max(1, int(q(1)))))
      call dgesvd('N', 'A', m, n, acopy, m, s, u, 1, vt, n, work, size(work), info)
      v = transpose(vt)
   end subroutine svd


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

   !> Natural logarithm of the determinant of a symmetric positive definite matrix (Cholesky);
   !> info > 0 if it is not positive definite
   pure subroutine logdet_spd(a, logdet, info)
      real(dp), intent(in) :: a(:, :)
      real(dp), intent(out) :: logdet
      integer, intent(out) :: info
      real(dp) :: l(size(a, 1), size(a, 2))
      integer :: i
      l = a
      call dpotrf('L', size(a, 1), l, size(a, 1), info)
      logdet = 0.0_dp
      if (info /= 0) return
      do i = 1, size(a, 1)
         logdet = logdet + 2.0_dp*log_dp(l(i, i))
      end do
   end subroutine logdet_spd
   !> a b, summed over k in increasing order
   pure function mat_mul_mm(a, b) result(c)
      real(dp), intent(in) :: a(:, :), b(:, :)
      real(dp) :: c(size(a, 1), size(b, 2))
      integer :: j, k
      c = 0.0_dp
      do j = 1, size(b, 2)
         do k = 1, size(a, 2)
            c(:, j) = c(:, j) + a(:, k)*b(k, j)
         end do
      end do
   end function mat_mul_mm

   !> a v, summed over k in increasing order
   pure function mat_mul_mv(a, v) result(c)
      real(dp), intent(in) :: a(:, :), v(:)
      real(dp) :: c(size(a, 1))
      integer :: k
      c = 0.0_dp
      do k = 1, size(a, 2)
         c = c + a(:, k)*v(k)
      end do
   end function mat_mul_mv
end module usharp_lapack
