!> Levenberg-Marquardt on a least-squares objective, with bounds: a variable at a bound that
!> the descent direction pushes outward is held there for the step, the step is projected
!> onto the box. The Jacobian comes from forward differences whose points are evaluated as
!> one batch (in parallel where the objective can). Damping after Marquardt (scaled by the
!> diagonal of J'J) with Nielsen's update of the damping factor from the gain ratio.
module usharp_levenberg
   use usharp_kinds, only: dp
   use usharp_error, only: error_type
   use usharp_optimiser, only: reason_itermax, reason_max_evals, least_squares_type, optimum_type
   use usharp_lapack, only: solve_dense, mat_mul
   implicit none
   private

   public :: levenberg_marquardt

contains

   !> Forward-difference Jacobian at x (residuals r there): step h, taken backwards where a
   !> forward step would leave the bounds. A column whose point failed is set to 0.
   subroutine fd_jacobian(obj, x, r, hi, h, jac, error)
      class(least_squares_type), intent(inout) :: obj
      real(dp), intent(in) :: x(:), r(:), hi(:), h
      real(dp), intent(out) :: jac(:, :)
      type(error_type), allocatable, intent(out) :: error
      real(dp) :: xs(size(x), size(x)), rs(size(r), size(x)), fs(size(x)), step(size(x))
      logical :: ok(size(x))
      integer :: j
      call fd_points(x, hi, h, xs, step)
      call obj%residuals(xs, rs, fs, ok, error)
      if (allocated(error)) return
      do j = 1, size(x)
         if (ok(j)) then
            jac(:, j) = (rs(:, j) - r)/step(j)
         else
            jac(:, j) = 0.0_dp
         end if
      end do
   end subroutine fd_jacobian

   !> The points of the forward-difference Jacobian at x: x + step(j) e_j, the step h taken
   !> backwards where a forward one would leave the bounds hi
   pure subroutine fd_points(x, hi, h, xs, step)
      real(dp), intent(in) :: x(:), hi(:), h
      real(dp), intent(out) :: xs(:, :), step(:)
      integer :: j
      do j = 1, size(x)
         step(j) = merge(-h, h, x(j) + h > hi(j))
         xs(:, j) = x
         xs(j, j) = x(j) + step(j)
      end do
   end subroutine fd_points

   !> Minimise sum(r**2) from x0 within [lo, hi]. h: difference step; ftol: stop when an
   !> accepted step lowers the objective by less than ftol relative and moves x by < 1e-4
   !> (on a difference Jacobian); also after itermax iterations or max_evals evaluations.
   subroutine levenberg_marquardt(obj, x0, lo, hi, h, ftol, itermax, max_evals, opt, error, jac0, &
                                  updates)
      class(least_squares_type), intent(inout) :: obj
      real(dp), intent(in) :: x0(:), lo(:), hi(:), h, ftol
      integer, intent(in) :: itermax, max_evals
      type(optimum_type), intent(out) :: opt
      type(error_type), allocatable, intent(out) :: error
      !> The difference Jacobian at x0 (inside the bounds) as this would compute it, when the
      !> caller has it already: the first iteration uses it
      real(dp), intent(in), optional :: jac0(:, :)
      !> Most accepted steps one difference Jacobian serves, brought up to date after each by
      !> Broyden's rank-1 update (Madsen, Nielsen and Tingleff 2004, sec. 3.4); 0 or 1 (0 the
      !> default): a difference Jacobian at every iteration. Where the search creeps along a
      !> curved valley, most iterations then cost one evaluation, not n + 1.
      integer, intent(in), optional :: updates
      integer :: n, m, iter, nevals, info
      real(dp), allocatable :: jac(:, :), r(:), rn(:, :)
      real(dp) :: x(size(x0)), xn(size(x0)), dx(size(x0)), g(size(x0)), a(size(x0), size(x0))
      real(dp) :: dmp(size(x0)), b(size(x0), 1), f, fn(1), lambda, nu, pred, gain, amax
      real(dp) :: xs_next(size(x0), size(x0)), step_next(size(x0))
      logical :: ok(1), done, by_sens, held(size(x0))
      integer :: j, nupd, max_updates

      n = size(x0)
      m = obj%nres()
      allocate (jac(m, n), r(m), rn(m, 1))
      x = min(max(x0, lo), hi)
      call obj%residuals(reshape(x, [n, 1]), rn, fn, ok, error)
      if (allocated(error)) return
      nevals = 1
      opt%x = x
      opt%f = fn(1)
      opt%iterations = 0
      opt%reason = 'the start point failed'
      if (.not. ok(1)) then
         opt%nevals = nevals
         return
      end if
      r = rn(:, 1)
      f = fn(1)
      lambda = -1.0_dp
      nu = 2.0_dp
      done = .false.
      max_updates = 0
      if (present(updates)) max_updates = max(updates, 0)
      nupd = max_updates
      by_sens = .false.
      opt%reason = reason_itermax
      do iter = 1, itermax
         if (nevals + n >= max_evals) then
            opt%reason = reason_max_evals
            exit
         end if
         if (iter == 1 .and. present(jac0)) then
            jac = jac0
            by_sens = .false.
            nupd = 0
         else if (nupd < max_updates .and. .not. by_sens) then
            continue
         else
            call obj%jacobian(x, jac, by_sens, error)
            if (allocated(error)) return
            nupd = 0
            if (by_sens) then
               nevals = nevals + 1
            else
               call fd_jacobian(obj, x, r, hi, h, jac, error)
               if (allocated(error)) return
               nevals = nevals + n
            end if
         end if
         opt%iterations = iter
         a = mat_mul(transpose(jac), jac)
         g = mat_mul(transpose(jac), r)
         amax = maxval([(a(j, j), j=1, n)])
         do j = 1, n
            dmp(j) = max(a(j, j), 1.0e-12_dp*amax, tiny(1.0_dp))
         end do
         ! A variable at a bound that the descent direction pushes outward is held there: the
         ! step of the others is solved without it. (Solved with it and then cut back to the
         ! bound, the others' step was made for a move it could not make, and the search crept
         ! along the bound: on Alloy 617 a quarter of a diagnosis's 100-iteration refits ended
         ! with the objective a hundredth of a percent below where it had been 50 before.)
         held = (x <= lo .and. g > 0.0_dp) .or. (x >= hi .and. g < 0.0_dp)
         if (lambda < 0.0_dp) lambda = 1.0e-3_dp
         do
            if (nevals >= max_evals) then
               opt%reason = reason_max_evals
               done = .true.
               exit
            end if
            b(:, 1) = -g
            if (any(held)) then
               call solve_dense(held_system(a + lambda*diag(dmp), held), b, info)
               where (held) b(:, 1) = 0.0_dp
            else
               call solve_dense(a + lambda*diag(dmp), b, info)
            end if
            if (info /= 0) then
               lambda = lambda*nu
               nu = 2.0_dp*nu
               cycle
            end if
            xn = min(max(x + b(:, 1), lo), hi)
            dx = xn - x
            if (maxval(abs(dx)) < 1.0e-12_dp) then
               if (nupd > 0) then
                  ! on an updated Jacobian: tried again with a difference one
                  nupd = max_updates
                  exit
               end if
               opt%reason = 'step too small'
               done = .true.
               exit
            end if
            ! If the trial is accepted, the next Jacobian's points come next: said ahead, so
            ! that idle capacity can start on them while the trial is simulated
            if (.not. by_sens .and. nevals + 1 + n < max_evals .and. iter < itermax .and. &
                nupd + 1 >= max_updates) then
               call fd_points(xn, hi, h, xs_next, step_next)
               call obj%prefetch(xs_next)
            end if
            call obj%residuals(reshape(xn, [n, 1]), rn, fn, ok, error)
            if (allocated(error)) return
            nevals = nevals + 1
            pred = -(2.0_dp*dot_product(g, dx) + dot_product(dx, mat_mul(a, dx)))
            if (ok(1) .and. fn(1) < f .and. pred > 0.0_dp) then
               gain = (f - fn(1))/pred
               lambda = lambda*max(1.0_dp/3.0_dp, 1.0_dp - (2.0_dp*gain - 1.0_dp)**3)
               nu = 2.0_dp
               if (f - fn(1) < ftol*f .and. maxval(abs(dx)) < 1.0e-4_dp) then
                  if (nupd == 0) then
                     opt%reason = 'relative decrease < eps'
                     done = .true.
                  else
                     ! Converged on an updated Jacobian: confirmed with a difference one
                     nupd = max_updates
                  end if
               end if
               if (.not. by_sens .and. nupd < max_updates) then
                  nupd = nupd + 1
                  ! Broyden: J + (r(xn) - r(x) - J dx) dx'/(dx'dx), the least change of J
                  ! that maps the step onto the change of the residuals it made (not when a
                  ! difference Jacobian comes next)
                  if (nupd < max_updates) then
                     r = rn(:, 1) - r - mat_mul(jac, dx)
                     do j = 1, n
                        jac(:, j) = jac(:, j) + r*(dx(j)/dot_product(dx, dx))
                     end do
                  end if
               end if
               x = xn
               r = rn(:, 1)
               f = fn(1)
               exit
            end if
            ! A step the updated Jacobian's model promised and the residuals did not give:
            ! the next try with a difference Jacobian
            if (nupd > 0 .and. nupd < max_updates) then
               nupd = max_updates
               exit
            end if
            lambda = lambda*nu
            nu = 2.0_dp*nu
            if (lambda > 1.0e16_dp) then
               opt%reason = 'no decrease along the damped steps'
               done = .true.
               exit
            end if
         end do
         if (done) exit
      end do
      opt%x = x
      opt%f = f
      opt%nevals = nevals

   contains

      !> The damped system with the held variables' rows and columns replaced by the identity
      !> (their step 0, with a right-hand side of 0 there)
      pure function held_system(m, held) result(k)
         real(dp), intent(in) :: m(:, :)
         logical, intent(in) :: held(:)
         real(dp) :: k(size(m, 1), size(m, 2))
         integer :: i
         k = m
         do i = 1, size(held)
            if (.not. held(i)) cycle
            k(i, :) = 0.0_dp
            k(:, i) = 0.0_dp
            k(i, i) = 1.0_dp
         end do
      end function held_system

      pure function diag(v) result(d)
         real(dp), intent(in) :: v(:)
         real(dp) :: d(size(v), size(v))
         integer :: k
         d = 0.0_dp
         do k = 1, size(v)
            d(k, k) = v(k)
         end do
      end function diag
   end subroutine levenberg_marquardt
end module usharp_levenberg
