!> Profile-likelihood intervals: where the curvature at an optimum says little (a weak effect,
!> a parameter that must stay positive, a valley of the objective), the interval of one search
!> coordinate is where the objective minimised over all the others stays within a threshold
!> of its minimum. The threshold is the chi-square 95 % point (1 degree of freedom) times the
!> variance scale of that coordinate: the ratio of its sandwich variance to its naive
!> (J'J)^-1 entry, so that near the optimum the interval is the Wald interval, and where the
!> objective is not quadratic the profile follows it. A positive coordinate is profiled in
!> its logarithm (it cannot cross zero).
module usharp_diagnose_profile
   use usharp_kinds, only: dp
   use usharp_lapack, only: mat_mul
   use usharp_math, only: exp_dp, log_dp
   use usharp_error, only: error_type
   use usharp_optimiser, only: least_squares_type, optimum_type
   use usharp_diagnose_journal, only: diagnose_journal
   use usharp_diagnose_units, only: lm_unit
   use usharp_identify, only: robust_covariance
   use usharp_effect_problem, only: effect_problem, failed_objective
   use usharp_diagnose_types, only: diagnose_context, diagnose_result
   use usharp_diagnose_numerics, only: jacobian, pseudo_inverse, effect_fit
   implicit none
   private

   public :: profile_interval, profile_result, chi2_95, f1_95, profile_leading, open_beyond_estimate

   !> Chi-square 95 % point, 1 degree of freedom
   real(dp), parameter :: chi2_95 = 3.841459_dp
   !> Steps out from the optimum on each side before the interval is called open
   integer, parameter :: max_steps = 14
   !> Steps a walk shortens (by 4 each) where the model fails to simulate before it leaves
   !> that end open
   integer, parameter :: max_failed = 8
   !> The leading effect's Wald interval is replaced by the profile when it crosses zero for
   !> a parameter that cannot, or its half-width exceeds this share of the value
   real(dp), parameter :: wald_rel_limit = 0.5_dp
   !> Evaluations of each refit of the constants along a profile
   integer, parameter :: profile_evals = 400
   !> Times a profile starts again from a lower point its walks met, and the least drop
   !> below the centre (a share of the threshold) that counts as one
   integer, parameter :: max_recentre = 2
   real(dp), parameter :: recentre_share = 0.05_dp

   !> The interval of one coordinate
   type :: profile_result
      real(dp) :: lo = 0.0_dp, hi = 0.0_dp   !< ends, in the coordinate's unit
      logical :: lo_open = .false.           !< the objective stays below the threshold up
      logical :: hi_open = .false.           !<   to the bound (or max_steps): not bounded
      real(dp) :: threshold = 0.0_dp         !< rise of the objective at the ends
      integer :: nevals = 0
      !> The point the interval is about (full x) and its objective: the given optimum, or
      !> a lower point the walks met (then the given one was not the optimum)
      real(dp), allocatable :: x_centre(:)
      real(dp) :: f_centre = 0.0_dp
   end type profile_result

   !> The problem with coordinate j held at a value: x of the others
   type, extends(least_squares_type) :: held_problem
      class(least_squares_type), allocatable :: base
      integer :: j = 0
      real(dp) :: value = 0.0_dp
   contains
      procedure :: residuals => held_residuals
      procedure :: nres => held_nres
      procedure :: eval => held_eval
   end type held_problem

contains

   !> 95 % point of F(1, nu), the square of Student's t at 97.5 % (Cornish-Fisher expansion
   !> in 1/nu, within 0.1 % for nu >= 5): the threshold factor when the variance scale is
   !> estimated from the residual with nu degrees of freedom (chi2_95 as nu grows)
   pure real(dp) function f1_95(nu) result(f)
      integer, intent(in) :: nu
      real(dp), parameter :: z = 1.959964_dp
      real(dp) :: t, v
      v = real(max(nu, 1), dp)
      t = z + (z**3 + z)/(4.0_dp*v) + (5.0_dp*z**5 + 16.0_dp*z**3 + 3.0_dp*z)/(96.0_dp*v**2) + &
          (3.0_dp*z**7 + 19.0_dp*z**5 + 17.0_dp*z**3 - 15.0_dp*z)/(384.0_dp*v**3)
      f = t**2
   end function f1_95

   !> Profile interval of coordinate j of obj at its optimum x_hat (objective f_hat) within
   !> [lo, hi]: the constants (every other coordinate) refitted by Levenberg-Marquardt
   !> (difference step h, at most max_evals evaluations each) at each trial value.
   subroutine profile_interval(obj, x_hat, f_hat, j, lo, hi, h, se, scale, log_scale, max_evals, &
                               pr, error, journal)
      class(least_squares_type), intent(in) :: obj
      real(dp), intent(in) :: x_hat(:), f_hat
      integer, intent(in) :: j
      real(dp), intent(in) :: lo(:), hi(:), h
      !> Wald standard error of coordinate j (its first step), x unit
      real(dp), intent(in) :: se
      !> Variance scale: the objective rises by chi2_95*scale at the 95 % ends (give
      !> f1_95(nu)/chi2_95 times it for a scale estimated with nu degrees of freedom)
      real(dp), intent(in) :: scale
      !> Profile log(x(j)) (x(j) > 0 kept)
      logical, intent(in) :: log_scale
      integer, intent(in) :: max_evals
      type(profile_result), intent(out) :: pr
      type(error_type), allocatable, intent(out) :: error
      !> The diagnosis's journal, whose units its refits are
      type(diagnose_journal), pointer, intent(in), optional :: journal
      type(diagnose_journal), pointer :: jr
      type(held_problem) :: hp
      !> The profile's centre: the lowest point met (full x) and its objective
      real(dp), allocatable :: xc(:)
      real(dp) :: fc
      integer :: side, nre
      real(dp) :: ends(2)
      logical :: open(2), lower
      jr => null()
      if (present(journal)) jr => journal
      allocate (hp%base, source=obj)
      hp%j = j
      pr%threshold = chi2_95*scale
      xc = x_hat
      fc = f_hat
      ! A walk that meets a point below the centre by more than the refits' own scatter
      ! shows that the centre was not the optimum: both walks again from the optimum
      ! refitted from that point, as the interval is where the objective stays within the
      ! threshold of its minimum
      do nre = 0, max_recentre
         lower = .false.
         do side = 1, 2
            call walk(merge(-1.0_dp, 1.0_dp, side == 1), nre < max_recentre, ends(side), &
                      open(side), lower)
            if (allocated(error)) return
            if (lower) exit
         end do
         if (.not. lower) exit
      end do
      pr%lo = ends(1)
      pr%hi = ends(2)
      pr%lo_open = open(1)
      pr%hi_open = open(2)
      pr%x_centre = xc
      pr%f_centre = fc
   contains
      !> From the centre in direction d until the objective has risen by the threshold;
      !> lower: it met a point below the centre (then the new centre, when may_recentre)
      subroutine walk(d, may_recentre, endpoint, is_open, lower)
         real(dp), intent(in) :: d
         logical, intent(in) :: may_recentre
         real(dp), intent(out) :: endpoint
         logical, intent(out) :: is_open
         logical, intent(inout) :: lower
         type(optimum_type) :: opt, again
         real(dp), allocatable :: xr(:), x0r(:)
         real(dp) :: u0, u, un, step, rise, rise_prev, ubound
         integer :: k, nfailed
         logical :: at_bound
         x0r = [xc(:j - 1), xc(j + 1:)]
         xr = x0r
         u0 = to_u(xc(j))
         if (d < 0.0_dp) then
            ubound = merge(to_u(lo(j)), -huge(1.0_dp), .not. log_scale .or. lo(j) > 0.0_dp)
         else
            ubound = to_u(hi(j))
         end if
         step = se
         if (log_scale) step = se/x_hat(j)
         if (.not. step > 0.0_dp .or. step > 1.0e6_dp) step = merge(0.1_dp, 0.1_dp*max(abs(u0), 1.0e-3_dp), log_scale)
         ! Start at half the Wald step: a curved profile may end well inside it
         step = 0.5_dp*step
         u = u0
         rise_prev = 0.0_dp
         is_open = .true.
         endpoint = from_u(u0)
         k = 0
         nfailed = 0
         do while (k < max_steps)
            un = u + d*step
            at_bound = d*(un - ubound) >= 0.0_dp
            if (at_bound) un = ubound
            hp%value = from_u(un)
            call refit(xr, opt)
            if (allocated(error)) return
            ! Each refit starts from the last point's constants and may end in another local
            ! minimum of them, a few units of the objective up or down: a rise that would end
            ! the walk, or jumps by more than half of it in one step, is checked by a refit
            ! from the centre's constants, and the lower of the two taken (the profile is a
            ! minimum, not the path of one chain of refits)
            ! (with no other coordinate there is nothing to refit)
            if (k > 0 .and. size(x0r) > 0 .and. opt%f < failed_objective) then
               if (opt%f - fc >= pr%threshold .or. opt%f - fc - rise_prev >= 0.5_dp*pr%threshold) then
                  call refit(x0r, again)
                  if (allocated(error)) return
                  if (again%f < opt%f) opt = again
               end if
            end if
            if (.not. opt%f < failed_objective) then
               ! A value at which the model fails to simulate says nothing of the likelihood
               ! (taken as a rise, a first Wald step of 22 peak stresses into it gave an
               ! initial back stress of 129 MPa the interval [129, 129]): a shorter step, and
               ! where short ones fail too, the end left open at the last value that simulated
               nfailed = nfailed + 1
               if (nfailed > max_failed) return
               ! (of the step taken: one cut to the search bound is not taken again)
               step = 0.25_dp*abs(un - u)
               cycle
            end if
            k = k + 1
            if (may_recentre .and. fc - opt%f > recentre_share*pr%threshold) then
               ! (the optimum itself, refitted from there with this coordinate free too)
               xc = [opt%x(:j - 1), hp%value, opt%x(j:)]
               fc = opt%f
               call lm_unit(jr, hp%base, xc, lo, hi, h, 1.0e-10_dp, 60, max_evals, again, error)
               if (allocated(error)) return
               pr%nevals = pr%nevals + again%nevals
               if (again%f < fc) then
                  xc = again%x
                  fc = again%f
               end if
               lower = .true.
               return
            end if
            rise = max(opt%f - fc, 0.0_dp)
            if (rise >= pr%threshold) then
               ! sqrt(rise) is about linear in the coordinate near the end
               endpoint = from_u(u + (un - u)*(sqrt(pr%threshold) - sqrt(rise_prev))/ &
                                 (sqrt(rise) - sqrt(rise_prev)))
               is_open = .false.
               return
            end if
            xr = opt%x
            u = un
            rise_prev = rise
            endpoint = from_u(u)
            if (at_bound) then
               ! Down to 0, the end of a parameter that cannot be negative (a delay, a rate):
               ! the interval reaches it, closed there ([0, 9.7e-3] s, not [open, 9.7e-3])
               if (d < 0.0_dp .and. lo(j) == 0.0_dp) then
                  endpoint = 0.0_dp
                  is_open = .false.
               end if
               return
            end if
            ! Longer steps while the objective rises slowly
            if (rise < 0.25_dp*pr%threshold) step = 2.0_dp*step
         end do
         ! A walk in the logarithm never meets 0: one that has gone six decades below the
         ! centre with the objective still within the threshold reaches it as well
         if (d < 0.0_dp .and. lo(j) == 0.0_dp .and. abs(endpoint) < 1.0e-6_dp*abs(x_hat(j))) then
            endpoint = 0.0_dp
            is_open = .false.
         end if
      end subroutine walk

      !> The other coordinates refitted from x_start at the held value hp%value
      subroutine refit(x_start, opt)
         real(dp), intent(in) :: x_start(:)
         type(optimum_type), intent(out) :: opt
         real(dp), allocatable :: lor(:), hir(:)
         if (size(x_start) > 0) then
            lor = [lo(:j - 1), lo(j + 1:)]
            hir = [hi(:j - 1), hi(j + 1:)]
            call lm_unit(jr, hp, x_start, lor, hir, h, 1.0e-10_dp, 60, max_evals, opt, error)
            if (allocated(error)) return
         else
            opt%x = x_start
            call hp%eval(opt%x, opt%f, error)
            if (allocated(error)) return
            opt%nevals = 1
         end if
         pr%nevals = pr%nevals + opt%nevals
      end subroutine refit

      pure real(dp) function to_u(x)
         real(dp), intent(in) :: x
         if (log_scale) then
            to_u = log_dp(max(x, tiny(1.0_dp)))
         else
            to_u = x
         end if
      end function to_u

      pure real(dp) function from_u(u)
         real(dp), intent(in) :: u
         if (log_scale) then
            from_u = exp_dp(u)
         else
            from_u = u
         end if
      end function from_u
   end subroutine profile_interval

   !> The leading effect's 95 % intervals from the profile likelihood where the curvature
   !> at its refit says little (see wald_rel_limit): the constants and the effect's other
   !> parameters refitted at each trial value; res%effects(leading)%p_profiled marks them
   subroutine profile_leading(ctx, res, error, lower)
      type(diagnose_context), intent(in) :: ctx
      type(diagnose_result), intent(inout) :: res
      type(error_type), allocatable, intent(out) :: error
      !> The lowest point (x of the leader's refit) that a profile's walks met below the
      !> refit's end point, when one did: the refit was not the optimum, and its figures are
      !> to come from there (unallocated: none)
      real(dp), allocatable, intent(out), optional :: lower(:)
      real(dp) :: f_lower
      type(effect_problem) :: ep
      type(profile_result) :: pr
      real(dp), allocatable :: r(:), jac(:, :), naive(:, :), cov(:, :), lo(:), hi(:), pscale(:)
      logical, allocatable :: nonneg(:)
      real(dp) :: se, scale
      integer :: nc, g, j
      logical :: ok
      if (res%leading == 0) return
      associate (e => res%effects(res%leading))
         if (.not. allocated(e%x_fit)) return
         ! (anew when the leader is profiled again from a lower point)
         e%p_profiled = spread(.false., 1, size(e%p))
         e%p_lo_open = spread(.false., 1, size(e%p))
         e%p_hi_open = spread(.false., 1, size(e%p))
         f_lower = e%f_after
         call effect_fit(ctx, e%k, ep, e%held, e%rate_start)
         if (size(e%x_fit) /= ep%nx()) return
         nc = size(ctx%prob%idx)
         call ep%bounds(lo, hi)
         call jacobian(ep, e%x_fit, ctx%h, r, jac, ok)
         if (.not. ok) return
         naive = pseudo_inverse(mat_mul(transpose(jac), jac))
         cov = robust_covariance(jac, r, naive)
         pscale = pack(ep%pscale, ep%pfree)
         nonneg = pack(ep%pnonneg, ep%pfree)
         do g = 1, size(e%p)
            j = nc + g
            se = sqrt(max(cov(j, j), 0.0_dp))
            ! (a Wald interval of a parameter that cannot be negative is cut at 0 there)
            if (.not. ((nonneg(g) .and. e%p_lo(g) <= 0.0_dp) .or. &
                       1.959964_dp*se*pscale(g) > wald_rel_limit*abs(e%p(g)))) cycle
            scale = e%f_after/max(size(r) - size(e%x_fit), 1)
            if (naive(j, j) > 0.0_dp .and. cov(j, j) > 0.0_dp) scale = cov(j, j)/naive(j, j)
            call profile_interval(ep, e%x_fit, e%f_after, j, lo, hi, ctx%h, se, scale, &
                                  nonneg(g) .and. e%x_fit(j) > 0.0_dp, profile_evals, pr, error, &
                                  ctx%journal)
            if (allocated(error)) return
            res%nevals = res%nevals + pr%nevals
            e%p_lo(g) = pr%lo*pscale(g)
            e%p_hi(g) = pr%hi*pscale(g)
            e%p_profiled(g) = .true.
            e%p_lo_open(g) = pr%lo_open
            e%p_hi_open(g) = pr%hi_open
            if (pr%f_centre < f_lower) then
               f_lower = pr%f_centre
               if (present(lower)) lower = pr%x_centre
            end if
         end do
         e%f_profile_low = f_lower
         call open_beyond_estimate(e%p, e%p_lo, e%p_hi, e%p_lo_open, e%p_hi_open)
      end associate
   end subroutine profile_leading

   !> The ends of 95 % intervals that leave out their estimate p marked open: a profile
   !> recentred on a lower point than the estimate's, and the search does not settle the end
   !> on the estimate's side (a specimen's dE/E of -0.181 came out [-0.224, -0.191], its
   !> refit at dD0/D0 = 57)
   pure subroutine open_beyond_estimate(p, p_lo, p_hi, lo_open, hi_open)
      real(dp), intent(in) :: p(:), p_lo(:), p_hi(:)
      logical, intent(inout) :: lo_open(:), hi_open(:)
      where (p > p_hi) hi_open = .true.
      where (p < p_lo) lo_open = .true.
   end subroutine open_beyond_estimate

   !> The full point of x of the other coordinates
   pure function full_x(self, x) result(xf)
      class(held_problem), intent(in) :: self
      real(dp), intent(in) :: x(:)
      real(dp) :: xf(size(x) + 1)
      xf = [x(:self%j - 1), self%value, x(self%j:)]
   end function full_x

   subroutine held_residuals(self, xs, rs, fs, ok, error)
      class(held_problem), intent(inout) :: self
      real(dp), intent(in) :: xs(:, :)
      real(dp), intent(out) :: rs(:, :)
      real(dp), intent(out) :: fs(:)
      logical, intent(out) :: ok(:)
      type(error_type), allocatable, intent(out) :: error
      real(dp) :: xf(size(xs, 1) + 1, size(xs, 2))
      integer :: k
      do k = 1, size(xs, 2)
         xf(:, k) = full_x(self, xs(:, k))
      end do
      call self%base%residuals(xf, rs, fs, ok, error)
   end subroutine held_residuals

   pure integer function held_nres(self) result(m)
      class(held_problem), intent(in) :: self
      m = self%base%nres()
   end function held_nres

   subroutine held_eval(self, x, f, error)
      class(held_problem), intent(inout) :: self
      real(dp), intent(in) :: x(:)
      real(dp), intent(out) :: f
      type(error_type), allocatable, intent(out) :: error
      call self%base%eval(full_x(self, x), f, error)
   end subroutine held_eval
end module usharp_diagnose_profile
