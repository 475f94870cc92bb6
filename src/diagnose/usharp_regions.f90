!> Where a fit's residual lies: each output point of a test is classed by the segment of its
!> load history (loading away from zero, unloading towards it, the reversal just after a turn,
!> hold), by its cycle, and as elastic or inelastic (|response| below or above a threshold).
!> For a set of points: share of the objective, RMS and mean signed error, the Wald-Wolfowitz
!> runs test on the signs of the error, and the ratio of the residual to the noise expected
!> from a noise level estimated from the data themselves.
module usharp_regions
   use usharp_kinds, only: dp
   use usharp_history, only: history_type
   implicit none
   private

   public :: point_classes, region_stat, region_of, noise_sd, runs_z, class_names, gap_se
   public :: noise_var_rse
   public :: class_loading, class_unloading, class_reversal, class_hold

   integer, parameter :: class_loading = 1, class_unloading = 2, class_reversal = 3, class_hold = 4
   character(len=9), parameter :: class_names(4) = ['loading  ', 'unloading', 'reversal ', 'hold     ']

   !> A turn counts once the control has come back by this fraction of its range (so the
   !> noise of a measured control does not make turns); a point is in the reversal while
   !> the control is within reversal_span of the range from the turn
   real(dp), parameter :: turn_hysteresis = 0.05_dp, reversal_span = 0.1_dp

   !> Relative standard error of noise_sd(y)**2, times sqrt(size(y)), for Gaussian white
   !> noise on a smooth response. Monte Carlo, 6000 draws each: 2.88, 2.83, 2.81 at 300, 600,
   !> 3000 points (above the 2.33 of the MAD of independent values: the second differences
   !> are correlated)
   real(dp), parameter :: noise_var_rse = 2.83_dp
   !> size(y) times the covariance of noise_sd(y)**2 and of one squared noise value, both
   !> over the true variance: the estimate and the objective rise together (Monte Carlo as
   !> above: 2.13, 2.01, 2.06)
   real(dp), parameter :: noise_cov = 2.05_dp

   !> Statistics of one region of the residual
   type :: region_stat
      character(len=40) :: test = ''
      character(len=24) :: label = ''
      integer :: n = 0
      real(dp) :: ssr = 0.0_dp        !< its part of the objective
      real(dp) :: noise = 0.0_dp      !< the part the noise level explains
      real(dp) :: gap = 0.0_dp        !< structured part: max(ssr - noise, 0)
      real(dp) :: rms = 0.0_dp        !< RMS error, response unit
      real(dp) :: bias = 0.0_dp       !< mean of data - model, response unit
      real(dp) :: z = 0.0_dp          !< runs-test z (negative: fewer runs than noise gives)
      real(dp) :: ratio = 0.0_dp      !< ssr/noise
      logical :: structured = .false.
   end type region_stat

contains

   !> Class, cycle (1-based, two turns each) of the points t of a test with control
   !> history hist; elastic where |y| < threshold
   pure subroutine point_classes(hist, t, y, threshold, cls, cycle, elastic)
      type(history_type), intent(in) :: hist
      real(dp), intent(in) :: t(:), y(:), threshold
      integer, intent(out) :: cls(:), cycle(:)
      logical, intent(out) :: elastic(:)
      real(dp), allocatable :: tturn(:), vturn(:)
      real(dp) :: range, v, slope, vext
      integer :: i, k, nturn, dir, it
      logical :: near_turn
      range = maxval(hist%v) - minval(hist%v)
      if (range <= 0.0_dp) range = 1.0_dp
      ! Turns: extremes of the control once it has come back by the hysteresis
      allocate (tturn(0), vturn(0))
      dir = 0
      vext = hist%v(1)
      it = 1
      do k = 2, size(hist%v)
         v = hist%v(k)
         if (dir >= 0 .and. v > vext .or. dir <= 0 .and. v < vext) then
            if (dir == 0) dir = merge(1, -1, v > vext)
            vext = v
            it = k
         else if (abs(v - vext) > turn_hysteresis*range) then
            tturn = [tturn, hist%t(it)]
            vturn = [vturn, vext]
            dir = -dir
            vext = v
            it = k
         end if
      end do
      nturn = 0
      k = 1
      do i = 1, size(t)
         do while (nturn < size(tturn))
            if (tturn(nturn + 1) > t(i)) exit
            nturn = nturn + 1
         end do
         do while (k < size(hist%t) - 1)
            if (hist%t(k + 1) > t(i)) exit
            k = k + 1
         end do
         ! A cycle holds two turns; the rise before a cycle's first turn counts with the last
         cycle(i) = max(1, (nturn + 1)/2)
         slope = (hist%v(k + 1) - hist%v(k))
         v = hist%v(k) + slope*(t(i) - hist%t(k))/(hist%t(k + 1) - hist%t(k))
         near_turn = .false.
         if (nturn > 0) near_turn = abs(v - vturn(nturn)) < reversal_span*range
         if (abs(slope) <= 1.0e-9_dp*range) then
            cls(i) = class_hold
         else if (near_turn) then
            cls(i) = class_reversal
         else if (v*slope > 0.0_dp) then
            cls(i) = class_loading
         else
            cls(i) = class_unloading
         end if
         elastic(i) = abs(y(i)) < threshold
      end do
   end subroutine point_classes

   !> Statistics of the points in mask: r weighted residuals, e = data - model (response
   !> unit), nv the noise variance of each weighted residual
   pure function region_of(test, label, mask, r, e, nv) result(st)
      character(len=*), intent(in) :: test, label
      logical, intent(in) :: mask(:)
      real(dp), intent(in) :: r(:), e(:), nv(:)
      type(region_stat) :: st
      st%test = test
      st%label = label
      st%n = count(mask)
      if (st%n == 0) return
      st%ssr = sum(r**2, mask)
      st%noise = sum(nv, mask)
      st%gap = max(st%ssr - st%noise, 0.0_dp)
      st%rms = sqrt(sum(e**2, mask)/st%n)
      st%bias = sum(e, mask)/st%n
      st%z = runs_z(pack(e, mask))
      st%ratio = st%ssr/max(st%noise, tiny(1.0_dp))
      ! Structured: far fewer sign runs than independent noise gives, and more residual than
      ! the noise explains
      st%structured = st%z < -3.0_dp .and. st%ratio > 1.1_dp
   end function region_of

   !> Wald-Wolfowitz runs test on the signs of e: (runs - mean)/sd; 0 if one sign only
   pure real(dp) function runs_z(e) result(z)
      real(dp), intent(in) :: e(:)
      real(dp) :: np, nm, n, mu, var
      integer :: i, runs
      z = 0.0_dp
      np = count(e > 0.0_dp)
      nm = count(e <= 0.0_dp)
      n = np + nm
      if (np < 1.0_dp .or. nm < 1.0_dp) return
      runs = 1
      do i = 2, size(e)
         if ((e(i) > 0.0_dp) .neqv. (e(i - 1) > 0.0_dp)) runs = runs + 1
      end do
      mu = 2.0_dp*np*nm/n + 1.0_dp
      var = (mu - 1.0_dp)*(mu - 2.0_dp)/(n - 1.0_dp)
      if (var <= 0.0_dp) return
      z = (real(runs, dp) - mu)/sqrt(var)
   end function runs_z

   !> Noise standard deviation of a sampled signal from its second differences, robustly
   !> (median absolute deviation): a smooth signal's second difference is far below the noise
   !> at the sampling rate, white noise gives var(d2) = 6 sd**2
   pure real(dp) function noise_sd(y) result(sd)
      real(dp), intent(in) :: y(:)
      real(dp), allocatable :: d(:)
      integer :: n
      n = size(y)
      sd = 0.0_dp
      if (n < 5) return
      d = abs(y(3:n) - 2.0_dp*y(2:n - 1) + y(1:n - 2))
      sd = 1.4826_dp*median(d)/sqrt(6.0_dp)
   end function noise_sd

   !> Standard error of a set's structured gap (objective - noise part) when its residual is
   !> noise alone: the chi-square scatter of the objective, the scatter of each test's noise
   !> estimate (noise_var_rse) less their covariance (noise_cov); tests independent
   pure real(dp) function gap_se(nv, test_of, npts, in_set) result(se)
      real(dp), intent(in) :: nv(:)        !< noise variance of each weighted residual
      integer, intent(in) :: test_of(:)    !< test of each residual
      integer, intent(in) :: npts(:)       !< points each test's noise sd was estimated from
      logical, intent(in) :: in_set(:)     !< the tests of the set
      real(dp) :: v
      integer :: i
      v = 2.0_dp*sum(nv**2, in_set(test_of))
      do i = 1, size(npts)
         if (in_set(i) .and. npts(i) > 0) &
            v = v + (noise_var_rse**2 - 2.0_dp*noise_cov)*sum(nv, test_of == i)**2/npts(i)
      end do
      se = sqrt(v)
   end function gap_se

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
end module usharp_regions
