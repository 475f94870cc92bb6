!> Nelder-Mead simplex search (Nelder and Mead 1965) with the standard coefficients
!> (reflection 1, expansion 2, contraction 1/2, shrink 1/2), points kept inside bounds
module usharp_nelder_mead
   use usharp_kinds, only: dp
   use usharp_error, only: error_type
   use usharp_optimiser, only: reason_max_evals, objective_type, optimum_type
   implicit none
   private

   public :: nelder_mead

contains

   !> Minimise obj from x0 within [lo, hi]; the first simplex has edges `size` along each
   !> coordinate (away from the nearer bound). Stop when the objective's spread over the
   !> simplex <= ftol*|f_best| and the simplex is smaller than 1e-8, or after max_evals.
   subroutine nelder_mead(obj, x0, lo, hi, size0, ftol, max_evals, opt, error)
      class(objective_type), intent(inout) :: obj
      real(dp), intent(in) :: x0(:), lo(:), hi(:), size0, ftol
      integer, intent(in) :: max_evals
      type(optimum_type), intent(out) :: opt
      type(error_type), allocatable, intent(out) :: error
      integer :: n, i, j, nevals, iter, order(size(x0) + 1)
      real(dp) :: p(size(x0), size(x0) + 1), f(size(x0) + 1), c(size(x0)), xr(size(x0)), &
                  xe(size(x0)), xc(size(x0)), fr, fe, fc
      n = size(x0)
      nevals = 0
      iter = 0
      p(:, 1) = min(max(x0, lo), hi)
      do j = 1, n
         p(:, j + 1) = p(:, 1)
         if (p(j, 1) + size0 <= hi(j)) then
            p(j, j + 1) = p(j, 1) + size0
         else
            p(j, j + 1) = p(j, 1) - size0
         end if
      end do
      do j = 1, n + 1
         call evaluate(p(:, j), f(j))
         if (allocated(error)) return
      end do
      opt%reason = reason_max_evals
      do while (nevals < max_evals)
         iter = iter + 1
         call sort_simplex()
         if (f(n + 1) - f(1) <= ftol*abs(f(1)) .and. &
             maxval(abs(p(:, 2:) - spread(p(:, 1), 2, n))) < 1.0e-8_dp) then
            opt%reason = 'simplex converged'
            exit
         end if
         c = sum(p(:, 1:n), dim=2)/real(n, dp)
         xr = clip(c + (c - p(:, n + 1)))
         call evaluate(xr, fr)
         if (allocated(error)) return
         if (fr < f(1)) then
            xe = clip(c + 2.0_dp*(c - p(:, n + 1)))
            call evaluate(xe, fe)
            if (allocated(error)) return
            if (fe < fr) then
               call replace_worst(xe, fe)
            else
               call replace_worst(xr, fr)
            end if
         else if (fr < f(n)) then
            call replace_worst(xr, fr)
         else
            ! Contract towards the better of the worst point and its reflection
            if (fr < f(n + 1)) then
               xc = c + 0.5_dp*(xr - c)
            else
               xc = c + 0.5_dp*(p(:, n + 1) - c)
            end if
            call evaluate(xc, fc)
            if (allocated(error)) return
            if (fc < min(fr, f(n + 1))) then
               call replace_worst(xc, fc)
            else
               do j = 2, n + 1
                  p(:, j) = p(:, 1) + 0.5_dp*(p(:, j) - p(:, 1))
                  call evaluate(p(:, j), f(j))
                  if (allocated(error)) return
               end do
            end if
         end if
      end do
      call sort_simplex()
      opt%x = p(:, 1)
      opt%f = f(1)
      opt%nevals = nevals
      opt%iterations = iter

   contains

      subroutine evaluate(x, fx)
         real(dp), intent(in) :: x(:)
         real(dp), intent(out) :: fx
         nevals = nevals + 1
         call obj%eval(x, fx, error)
      end subroutine evaluate

      pure function clip(x) result(y)
         real(dp), intent(in) :: x(:)
         real(dp) :: y(size(x))
         y = min(max(x, lo), hi)
      end function clip

      subroutine replace_worst(x, fx)
         real(dp), intent(in) :: x(:), fx
         p(:, n + 1) = x
         f(n + 1) = fx
      end subroutine replace_worst

      !> Order the vertices by objective (insertion sort: n is small)
      subroutine sort_simplex()
         real(dp) :: pt(size(x0)), ft
         integer :: k, m
         do k = 2, n + 1
            ft = f(k)
            pt = p(:, k)
            m = k - 1
            do while (m >= 1)
               if (f(m) <= ft) exit
               f(m + 1) = f(m)
               p(:, m + 1) = p(:, m)
               m = m - 1
            end do
            f(m + 1) = ft
            p(:, m + 1) = pt
         end do
         order = 0
      end subroutine sort_simplex
   end subroutine nelder_mead
end module usharp_nelder_mead
