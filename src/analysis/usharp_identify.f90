!> Identifiability at a fit's optimum: the Jacobian of the weighted residuals with respect to
!> log10 of the fitted constants (central differences), its singular values, the parameter
!> covariance (heteroscedasticity-consistent sandwich (J'J)^-1 J' diag(r**2) J (J'J)^-1), 
!> correlations, 95 % confidence intervals, constants at a bound, and the poorly determined directions in words.
module usharp_identify
   use usharp_kinds, only: dp
   use usharp_math, only: log10_dp, pow10_dp
   use usharp_error, only: error_type, fatal_error, stat_failure
   use usharp_strings, only: str, real_str, report_line_len
   use usharp_model, only: constant_names
   use usharp_objective, only: fit_problem, eval_ok, message_len
   use usharp_lapack, only: svd, mat_mul
   implicit none
   private

   public :: identify_result, identify_at, identify_report, jacobian_log10, robust_covariance, &
             chi2_quantile_95

   !> A direction is poorly determined when its singular value is below this fraction of the
   !> largest (a relative change of 1e-3 in the residuals for a unit step in log10)
   real(dp), parameter :: weak_ratio = 1.0e-3_dp
   !> A determined constant is determined loosely when its 95 % interval spans more than this
   !> many decades: the direction is not weak, yet the tests bound the constant only to a
   !> factor of ten or worse (C2 within [1e-6, 1e4] was reported as determined)
   real(dp), parameter :: loose_decades = 1.0_dp
   !> The constants are taken for an optimum of the tests while a Gauss-Newton step from them
   !> (over the constants not at a bound) would lower the sum of squares by less than this
   !> share: the report's s^2 and intervals assume one
   real(dp), parameter :: optimum_fall = 0.01_dp
   !> An RMS error (% of a test's peak) within the integrators' accuracy (1e-4 of the peak)
   real(dp), parameter :: exact_rms = 0.01_dp

   type :: identify_result
      character(len=:), allocatable :: names(:)
      real(dp), allocatable :: c(:)          !< constants, physical units
      real(dp), allocatable :: sv(:)         !< singular values of J (log10 columns)
      real(dp), allocatable :: v(:, :)       !< right singular vectors (columns)
      real(dp), allocatable :: se(:)         !< standard error of log10 c
      real(dp), allocatable :: lo95(:), hi95(:)  !< 95 % confidence interval of c
      !> Simultaneous 95 % intervals: the joint confidence ellipsoid of all fitted constants
      !> projected on each axis (Scheffe); all of them hold together with 95 % confidence
      real(dp), allocatable :: lo_joint(:), hi_joint(:)
      integer :: rank = 0                    !< directions that carry information
      real(dp), allocatable :: corr(:, :)
      logical, allocatable :: at_bound(:), determined(:)
      !> determined, but its 95 % interval spans more than loose_decades (a factor of 10)
      logical, allocatable :: loose(:)
      character(len=report_line_len), allocatable :: words(:)
      real(dp) :: s2 = 0.0_dp, ssr = 0.0_dp
      !> The share of ssr a Gauss-Newton step would remove (see optimum_fall)
      real(dp) :: gn_fall = 0.0_dp
      integer :: m = 0, nevals = 0
   end type identify_result

contains

   !> Central-difference Jacobian of the residuals with respect to x = log10 c (step h); the
   !> points are simulated as one parallel batch. r0: residuals at x.
   subroutine jacobian_log10(prob, x, h, r0, jac, f0, nevals, error, spread)
      type(fit_problem), intent(in) :: prob
      real(dp), intent(in) :: x(:), h
      real(dp), allocatable, intent(out) :: r0(:), jac(:, :)
      real(dp), intent(out) :: f0
      integer, intent(out) :: nevals
      type(error_type), allocatable, intent(out) :: error
      !> Ranks in lockstep split the points (see fit_problem's batch)
      logical, intent(in), optional :: spread
      integer :: n, m, j
      real(dp), allocatable :: xs(:, :), rs(:, :), fs(:), pt(:, :)
      integer, allocatable :: status(:)
      character(len=message_len), allocatable :: msg(:)
      n = size(x)
      m = prob%nres()
      allocate (xs(n, 2*n + 1), rs(m, 2*n + 1), fs(2*n + 1), pt(size(prob%targets), 2*n + 1), &
                status(2*n + 1), msg(2*n + 1))
      do j = 1, 2*n + 1
         xs(:, j) = x
      end do
      do j = 1, n
         xs(j, 2*j) = x(j) + h
         xs(j, 2*j + 1) = x(j) - h
      end do
      call prob%batch(xs, 0, rs, fs, pt, status, msg, 'identify', spread)
      nevals = 2*n + 1
      do j = 1, 2*n + 1
         if (status(j) /= eval_ok) then
            call fatal_error(error, 'identifiability: simulation failed near the optimum: '// &
                             trim(msg(j)), stat_failure)
            return
         end if
      end do
      r0 = rs(:, 1)
      f0 = fs(1)
      allocate (jac(m, n))
      do j = 1, n
         jac(:, j) = (rs(:, 2*j) - rs(:, 2*j + 1))/(2.0_dp*h)
      end do
   end subroutine jacobian_log10

   !> Heteroscedasticity-consistent covariance of least-squares estimates (the sandwich
   !> (J'J)^+ J' diag(r**2) J (J'J)^+, with the small-sample factor m/(m - p)): jac (m x p)
   !> of the residuals r, pinv = (J'J)^+
   pure function robust_covariance(jac, r, pinv) result(cov)
      real(dp), intent(in) :: jac(:, :), r(:), pinv(:, :)
      real(dp) :: cov(size(pinv, 1), size(pinv, 2))
      real(dp) :: meat(size(jac, 2), size(jac, 2))
      integer :: i, j, m, p
      m = size(jac, 1)
      p = size(jac, 2)
      do j = 1, p
         do i = 1, j
            meat(i, j) = sum((r*jac(:, i))*(r*jac(:, j)))
            meat(j, i) = meat(i, j)
         end do
      end do
      cov = mat_mul(pinv, mat_mul(meat, pinv))*real(m, dp)/real(max(m - p, 1), dp)
   end function robust_covariance

   !> The identifiability of the fitted constants of prob at c (physical units)
   subroutine identify_at(prob, c, h, res, error, spread)
      type(fit_problem), intent(in) :: prob
      real(dp), intent(in) :: c(:), h
      type(identify_result), intent(out) :: res
      type(error_type), allocatable, intent(out) :: error
      !> Every rank calls this with the same c and they split the Jacobian's points
      logical, intent(in), optional :: spread
      type(fit_problem) :: logprob
      real(dp), allocatable :: r0(:), jac(:, :), cov(:, :), pinv(:, :)
      real(dp) :: f0, t95, q95, lo, hi
      integer :: n, i, j, info
      integer :: tied(size(c))
      logical :: wide(size(c))
      n = size(c)
      tied = 0
      logprob = prob
      logprob%cfg%fit%log_search = .true.
      call jacobian_log10(logprob, log10_dp(c), h, r0, jac, f0, res%nevals, error, spread)
      if (allocated(error)) return
      res%names = constant_names(prob%cfg%model, prob%idx)
      res%c = c
      res%m = size(r0)
      res%ssr = f0
      res%s2 = f0/real(max(res%m - n, 1), dp)
      allocate (res%sv(n), res%v(n, n))
      call svd(jac, res%sv, res%v, info)
      if (info /= 0) then
         call fatal_error(error, 'identifiability: the SVD of the Jacobian failed (info '// &
                          str(info)//')', stat_failure)
         return
      end if
      ! (J'J)^+ = V S^-2 V' over the directions that carry information
      allocate (pinv(n, n))
      pinv = 0.0_dp
      do i = 1, n
         if (res%sv(i) > weak_ratio*res%sv(1) .and. res%sv(i) > 0.0_dp) then
            do j = 1, n
               pinv(:, j) = pinv(:, j) + res%v(:, i)*res%v(j, i)/res%sv(i)**2
            end do
         end if
      end do
      ! The weighted residuals of Eq. 7 do not share one variance (1/n per test, w = 2.5 above
      ! SIG), so s2 (J'J)^-1 would be too narrow for constants set by the tests with the
      ! noisier residuals: the sandwich (J'J)^+ J' diag(r**2) J (J'J)^+ m/(m - p) holds
      ! whatever the variance of each residual
      cov = robust_covariance(jac, r0, pinv)
      res%se = [(sqrt(max(cov(i, i), 0.0_dp)), i=1, n)]
      t95 = t_quantile_975(res%m - n)
      res%lo95 = c*pow10_dp(-t95*res%se)
      res%hi95 = c*pow10_dp(t95*res%se)
      ! Marginal intervals each miss with 5 %; for a statement about all constants at once
      ! (the A2-B-n valley makes their errors move together) the ellipsoid's shadow is needed
      res%rank = count(res%sv > weak_ratio*res%sv(1) .and. res%sv > 0.0_dp)
      q95 = sqrt(chi2_quantile_95(max(res%rank, 1)))
      res%lo_joint = c*pow10_dp(-q95*res%se)
      res%hi_joint = c*pow10_dp(q95*res%se)
      allocate (res%corr(n, n))
      do i = 1, n
         do j = 1, n
            res%corr(i, j) = cov(i, j)/max(res%se(i)*res%se(j), tiny(1.0_dp))
         end do
      end do
      allocate (res%at_bound(n), res%determined(n))
      do j = 1, n
         lo = prob%cfg%fit%lower(prob%idx(j))
         hi = prob%cfg%fit%upper(prob%idx(j))
         res%at_bound(j) = abs(log10_dp(c(j)/lo)) < 1.0e-6_dp .or. abs(log10_dp(hi/c(j))) < 1.0e-6_dp
         ! Determined: no weight in the weak directions, not at a bound
         res%determined(j) = .not. (res%at_bound(j) .or. in_weak_direction(res, j))
         ! Nor one whose 95 % interval is wider than its search bounds (in decades): the
         ! tests do not bound it within them (A2 of a creep test alone: 326 decades)
         wide(j) = res%determined(j) .and. res%se(j) > 0.0_dp .and. &
                   2.0_dp*t95*res%se(j) > log10_dp(hi) - log10_dp(lo)
         if (wide(j)) res%determined(j) = .false.
      end do
      res%gn_fall = gauss_newton_fall(jac, r0, .not. res%at_bound)
      ! Tests fitted to within the integrator's accuracy (the RMS error below exact_rms % of
      ! each test's peak: the sum of squares of Eq. 7's residuals is the objective, a mean
      ! square error in % per test) are at an optimum whatever a step would take off that
      ! error (noise-free data at the constants that made them: 83.5 % of s^2 = 4.2e-10)
      if (sum(r0**2) < exact_rms**2*size(prob%targets)) res%gn_fall = 0.0_dp
      ! A constant tied to an undetermined one (|correlation| > 0.99) is not determined alone
      do j = 1, n
         if (.not. res%determined(j)) cycle
         do i = 1, n
            if (i /= j .and. .not. res%determined(i) .and. .not. res%at_bound(i) .and. &
                abs(res%corr(i, j)) > 0.99_dp) then
               tied(j) = i
               exit
            end if
         end do
      end do
      ! Settled before the words and the status: a tied constant is not determined, so not
      ! loosely determined either
      where (tied > 0) res%determined = .false.
      call describe(res)
      do j = 1, n
         if (wide(j)) res%words = [character(len=report_line_len) :: res%words, trim(res%names(j))// &
            ': its 95 % interval spans '//real_str(2.0_dp*t95*res%se(j), 'es8.1')//' decades, more '// &
            'than its search bounds ('//real_str(log10_dp(prob%cfg%fit%upper(prob%idx(j))/ &
            prob%cfg%fit%lower(prob%idx(j))), 'es8.1')//'): not determined within them']
      end do
      do j = 1, n
         if (tied(j) == 0) cycle
         res%words = [character(len=report_line_len) :: res%words, trim(res%names(j))//' is tied to '// &
            trim(res%names(tied(j)))//' (correlation '//real_str(res%corr(j, tied(j)), 'f5.2')// &
            '): not determined on its own']
      end do
   end subroutine identify_at

   !> Whether constant j weighs in a direction the tests barely see (singular value at most
   !> weak_ratio of the largest, the constant's share of it above 0.3)
   pure logical function in_weak_direction(res, j) result(weak)
      type(identify_result), intent(in) :: res
      integer, intent(in) :: j
      weak = any(res%sv <= weak_ratio*res%sv(1) .and. abs(res%v(j, :)) > 0.3_dp)
   end function in_weak_direction

   !> The share of the sum of squares r'r that a Gauss-Newton step over the free columns of
   !> jac would remove, in the directions that carry information (as the intervals take
   !> them): about 0 at an optimum of the tests, up to 1 far from one
   pure real(dp) function gauss_newton_fall(jac, r, free) result(share)
      real(dp), intent(in) :: jac(:, :), r(:)
      logical, intent(in) :: free(:)
      real(dp), allocatable :: jf(:, :), g(:), sv(:), v(:, :)
      integer :: i, k, info
      share = 0.0_dp
      if (.not. any(free) .or. .not. dot_product(r, r) > 0.0_dp) return
      jf = jac(:, pack([(k, k=1, size(free))], free))
      allocate (sv(size(jf, 2)), v(size(jf, 2), size(jf, 2)))
      call svd(jf, sv, v, info)
      if (info /= 0 .or. .not. sv(1) > 0.0_dp) return
      g = mat_mul(transpose(jf), r)
      do i = 1, size(sv)
         if (sv(i) > weak_ratio*sv(1)) share = share + (dot_product(v(:, i), g)/sv(i))**2
      end do
      share = share/dot_product(r, r)
   end function gauss_newton_fall

   !> Words for the weak directions and the bounds
   subroutine describe(res)
      type(identify_result), intent(inout) :: res
      integer :: i, j, k, n, big(size(res%c)), nbig, i2
      character(len=:), allocatable :: line
      real(dp) :: e, span
      n = size(res%c)
      allocate (res%words(0))
      do j = 1, n
         if (res%at_bound(j)) res%words = [character(len=report_line_len) :: res%words, &
            trim(res%names(j))//' sits at a bound of the search ('//real_str(res%c(j), 'es10.3')// &
            '): not determined within the bounds']
      end do
      do i = 1, n
         if (res%sv(i) > weak_ratio*res%sv(1)) cycle
         nbig = 0
         do j = 1, n
            if (abs(res%v(j, i)) > 0.3_dp) then
               nbig = nbig + 1
               big(nbig) = j
            end if
         end do
         if (nbig == 1) then
            ! Alone in the direction only if its own column is as weak: a constant of strong
            ! effect that another makes up at a much larger scale (B against Q at one
            ! temperature, Q/(R T) = 37 times) stands nearly alone in v but is tied to it
            ! (its column, sum over l of (sv_l v_jl)**2, ten times v's singular value or more)
            j = big(1)
            k = partner(j, i)
            if (k > 0 .and. sqrt(sum((res%sv*res%v(j, :))**2)) > 10.0_dp*res%sv(i)) then
               line = 'only a combination of '//trim(res%names(j))//' and '//trim(res%names(k))// &
                      ' is determined: a change of '//trim(res%names(j))//' is made up by one of '// &
                      trim(res%names(k))
            else
               line = trim(res%names(j))//' has (almost) no effect on these tests'
            end if
         else if (nbig == 2) then
            ! Invariant along v: only c_j * c_k**e with e = -v_j/v_k is determined
            j = big(1)
            k = big(2)
            e = -res%v(j, i)/res%v(k, i)
            ! Unless another weak direction holds the same two alone: then neither, nor any
            ! combination of them, is (A1*A2 and A2/A1 each "determined" would make both so)
            i2 = other_weak(i, j, k)
            if (i2 > 0) then
               if (i2 < i) cycle
               res%words = [character(len=report_line_len) :: res%words, 'neither '// &
                  trim(res%names(j))//' nor '//trim(res%names(k))//' is determined, nor a '// &
                  'combination of them (singular values '//real_str(res%sv(i)/res%sv(1), 'es8.1')// &
                  ' and '//real_str(res%sv(i2)/res%sv(1), 'es8.1')//' of the largest)']
               cycle
            end if
            if (abs(e + 1.0_dp) < 0.15_dp) then
               line = 'only '//trim(res%names(k))//'/'//trim(res%names(j))//' is determined'
            else if (abs(e - 1.0_dp) < 0.15_dp) then
               line = 'only '//trim(res%names(j))//'*'//trim(res%names(k))//' is determined'
            else
               line = 'only '//trim(res%names(j))//'*'//trim(res%names(k))//'^'// &
                      real_str(e, 'f0.2')//' is determined'
            end if
         else
            line = 'only combinations of'
            do k = 1, nbig
               line = line//' '//trim(res%names(big(k)))
            end do
            line = line//' are determined, not each'
         end if
         res%words = [character(len=report_line_len) :: res%words, line//' (singular value '// &
            real_str(res%sv(i)/res%sv(1), 'es8.1')//' of the largest)']
      end do
      allocate (res%loose(n))
      res%loose = .false.
      do j = 1, n
         if (.not. res%determined(j)) cycle
         if (.not. (res%lo95(j) > 0.0_dp .and. res%hi95(j) > 0.0_dp)) cycle
         ! The decades as a difference of logarithms: the ratio overflows for an interval
         ! of 1e-167 to 1e159
         span = log10_dp(res%hi95(j)) - log10_dp(res%lo95(j))
         res%loose(j) = span > loose_decades
         if (res%loose(j)) res%words = [character(len=report_line_len) :: res%words, trim(res%names(j))// &
            ': its 95 % interval spans '//real_str(span, 'f0.1')// &
            ' decades; these tests bound it only loosely']
      end do
      if (size(res%words) == 0 .and. all(res%determined)) res%words = [character(len=report_line_len) :: &
         'every fitted constant is determined by these tests']
   contains
      !> The constant beside j with the largest share of singular vector i (0 if none has
      !> a share above rounding)
      pure integer function partner(j, i) result(k)
         integer, intent(in) :: j, i
         integer :: m
         real(dp) :: vmax
         k = 0
         vmax = 1.0e-6_dp
         do m = 1, size(res%c)
            if (m == j) cycle
            if (abs(res%v(m, i)) > vmax) then
               vmax = abs(res%v(m, i))
               k = m
            end if
         end do
      end function partner

      !> Another weak direction than i (the first) of the same two constants j and k alone
      !> (the two with a share as large as in a direction's description; 0 if none)
      pure integer function other_weak(i, j, k) result(i2)
         integer, intent(in) :: i, j, k
         do i2 = 1, size(res%sv)
            if (i2 == i .or. res%sv(i2) > weak_ratio*res%sv(1)) cycle
            if (abs(res%v(j, i2)) > 0.3_dp .and. abs(res%v(k, i2)) > 0.3_dp .and. &
                count(abs(res%v(:, i2)) > 0.3_dp) == 2) return
         end do
         i2 = 0
      end function other_weak
   end subroutine describe

   !> The report as lines of text
   function identify_report(res) result(lines)
      type(identify_result), intent(in) :: res
      character(len=report_line_len), allocatable :: lines(:)
      character(len=:), allocatable :: line
      integer :: i, j, n
      n = size(res%c)
      lines = [character(len=report_line_len) :: 'identifiability at '// &
         trim(merge('the optimum    ', 'these constants', res%gn_fall < optimum_fall))// &
         ' ('//str(res%m)//' residuals, '//str(n)//' constant'//trim(merge('s', ' ', n /= 1))// &
         ', s^2 = SSR/(m-p) = '// &
         real_str(res%s2, 'es10.3')//')']
      if (.not. res%gn_fall < optimum_fall) lines = [character(len=report_line_len) :: lines, &
         '  - not an optimum of these tests: a Gauss-Newton step would lower the sum of squares by '// &
         real_str(100.0_dp*res%gn_fall, 'f5.1')//' %; s^2 and the intervals below assume an optimum, '// &
         'so they only indicate what they would be at one nearby']
      lines = [character(len=report_line_len) :: lines, &
         '  singular values of the scaled Jacobian (d residual / d log10 constant), relative:']
      line = '   '
      do i = 1, n
         line = line//' '//real_str(res%sv(i)/res%sv(1), 'es9.2')
      end do
      lines = [character(len=report_line_len) :: lines, line, &
         '  constant      value       95 % interval (sandwich)    simultaneous 95 % ('// &
         str(res%rank)//' direction'//trim(merge('s', ' ', res%rank /= 1))//')   status']
      do j = 1, n
         line = '  '//res%names(j)//'  '//real_str(res%c(j), 'es13.5')//'  '
         ! At a bound the interval says how far the tests would move it off the bound, unless
         ! it lies in a weak direction too: then it is the same artefact as below
         if (res%determined(j) .or. (res%at_bound(j) .and. .not. in_weak_direction(res, j))) then
            line = line//'['//real_str(res%lo95(j), 'es11.4')//', '// &
                   real_str(res%hi95(j), 'es11.4')//']  ['//real_str(res%lo_joint(j), 'es11.4')// &
                   ', '//real_str(res%hi_joint(j), 'es11.4')//']  '
         else
            ! A linearised interval of an undetermined constant is an artefact of round-off in
            ! a near-null direction: print none rather than a number a reader would trust
            line = line//'[         none           ]  [         none           ]  '
         end if
         if (res%at_bound(j)) then
            line = line//'at a bound'
         else if (res%loose(j)) then
            line = line//'loosely determined'
         else if (res%determined(j)) then
            line = line//'determined'
         else
            line = line//'not determined'
         end if
         lines = [character(len=report_line_len) :: lines, line]
      end do
      lines = [character(len=report_line_len) :: lines, '  correlations:']
      do i = 1, n
         line = '    '//res%names(i)
         do j = 1, n
            line = line//' '//real_str(res%corr(i, j), 'f6.2')
         end do
         lines = [character(len=report_line_len) :: lines, line]
      end do
      do i = 1, size(res%words)
         lines = [character(len=report_line_len) :: lines, '  - '//trim(res%words(i))]
      end do
   end function identify_report

   !> 95 % quantile of chi-square with nu degrees of freedom: tabulated to nu = 10,
   !> Wilson-Hilferty above (within 0.1 % there: 43.77 for nu = 30)
   pure real(dp) function chi2_quantile_95(nu) result(q)
      integer, intent(in) :: nu
      real(dp), parameter :: z = 1.644853626951472_dp
      real(dp), parameter :: table(10) = [3.841459_dp, 5.991465_dp, 7.814728_dp, 9.487729_dp, &
         11.070498_dp, 12.591587_dp, 14.067140_dp, 15.507313_dp, 16.918978_dp, 18.307038_dp]
      real(dp) :: v
      if (nu <= size(table)) then
         q = table(max(nu, 1))
         return
      end if
      v = 2.0_dp/(9.0_dp*real(nu, dp))
      q = real(nu, dp)*(1.0_dp - v + z*sqrt(v))**3
   end function chi2_quantile_95

   !> 97.5 % quantile of Student's t with nu degrees of freedom (Cornish-Fisher expansion,
   !> better than 1e-3 for nu >= 5)
   pure real(dp) function t_quantile_975(nu) result(t)
      integer, intent(in) :: nu
      real(dp), parameter :: z = 1.959963984540054_dp
      real(dp) :: v
      v = real(max(nu, 1), dp)
      t = z + (z**3 + z)/(4.0_dp*v) + (5.0_dp*z**5 + 16.0_dp*z**3 + 3.0_dp*z)/(96.0_dp*v**2) &
          + (3.0_dp*z**7 + 19.0_dp*z**5 + 17.0_dp*z**3 - 15.0_dp*z)/(384.0_dp*v**3)
   end function t_quantile_975
end module usharp_identify
