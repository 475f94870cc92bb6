!> Where a fit's residual lies: each output point of a test is classed by the segment of its
!> load history (loading away from zero, unloading towards it, the reversal just after a turn,
!> hold) and its cycle, both from the kinematics of the control with hysteresis against its
!> noise and quantisation, and as elastic or inelastic from the model's own inelastic rate.
!> For a set of points: share of the objective, RMS and mean signed error, the Wald-Wolfowitz
!> runs test on the signs of the error, and the ratio of the residual to the noise expected
!> from a noise level estimated from the data themselves.
module usharp_regions
   use usharp_kinds, only: dp
   use usharp_math, only: exp_dp, log_dp, sincos_turn
   use usharp_history, only: history_type
   use usharp_forcing, only: noise_sd
   implicit none
   private

   public :: point_classes, region_stat, region_of, noise_sd, runs_z, class_names, gap_se
   public :: noise_var_rse, inelastic_points, kinematics_of, control_kinematics
   public :: serration_stat, serration_of, serration_in_runs
   public :: class_loading, class_unloading, class_reversal, class_hold

   integer, parameter :: class_loading = 1, class_unloading = 2, class_reversal = 3, class_hold = 4
   character(len=9), parameter :: class_names(4) = ['loading  ', 'unloading', 'reversal ', 'hold     ']

   !> A turn counts once the control has come back by this fraction of its range, and by
   !> turn_quanta quanta and turn_noise noise standard deviations of a measured control (so
   !> noise, quantisation and the dips of serrations make no turns); a point is in the
   !> reversal while the control is within reversal_span of the range from the turn
   real(dp), parameter :: turn_hysteresis = 0.05_dp, reversal_span = 0.1_dp
   !> ... and within this share of the travel of its branch (turn to turn)
   real(dp), parameter :: reversal_branch = 0.3_dp
   real(dp), parameter :: turn_quanta = 10.0_dp, turn_noise = 6.0_dp
   !> A control is quantised (measured) when its smallest step is below this fraction of its
   !> range; its noise is estimated when it has at least dense_corners corners
   real(dp), parameter :: quantum_fraction = 0.01_dp
   integer, parameter :: dense_corners = 50
   !> Hold: the control, averaged over +- hold_smooth samples, within hold_quanta quanta
   !> (hold_noise noise sd) for longer than hold_crossings times the time the moving control
   !> takes to cross that band, and hold_samples samples (the band holds the extremes of the
   !> averaged noise over some hundred samples)
   real(dp), parameter :: hold_quanta = 6.0_dp, hold_noise = 6.0_dp
   integer, parameter :: hold_smooth = 2
   real(dp), parameter :: hold_crossings = 10.0_dp, hold_samples = 5.0_dp
   !> Inelastic: the inelastic strain's change over +- rate_window points exceeds this share
   !> of the total strain's change, and inelastic_floor of its mean change over a window
   real(dp), parameter :: inelastic_share = 0.1_dp, inelastic_floor = 1.0e-3_dp
   integer, parameter :: rate_window = 2
   !> Serrations: oscillations of periods from 2 to serration_max_period samples, named when
   !> white noise gives so strong a peak with a chance below serration_p
   integer, parameter :: serration_max_period = 64
   real(dp), parameter, public :: serration_p = 1.0e-4_dp

   !> Turns, holds and resolution of a test's control
   type :: control_kinematics
      real(dp) :: range = 1.0_dp               !< max - min of the control
      real(dp) :: quantum = 0.0_dp             !< its step (0: not quantised)
      real(dp) :: noise = 0.0_dp               !< its noise sd (0: not estimated)
      real(dp) :: band = 0.0_dp                !< band of a hold
      integer :: dir0 = 1                      !< direction of the first branch
      real(dp), allocatable :: tturn(:), vturn(:)  !< turns: time (s), value
      logical, allocatable :: hold(:)          !< each history segment: in a hold
   end type control_kinematics

   !> An oscillation in a residual (Fisher's g test on its periodogram over short periods)
   type :: serration_stat
      integer :: n = 0                 !< points tested
      real(dp) :: p = 1.0_dp           !< chance that white noise gives so strong a peak
      real(dp) :: period = 0.0_dp      !< samples
      real(dp) :: amplitude = 0.0_dp   !< response unit
   end type serration_stat

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
      character(len=256) :: test = '' !< the test's name, "(held out)" appended
      character(len=48) :: label = ''
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

   !> Class and cycle (1-based, two turns each) of the points t (s) of a test whose control
   !> (strain or stress) follows hist, from the kinematics alone, robust to a measured
   !> control's noise and quantisation:
   !> - a turn counts once the control has come back from its extreme by more than the
   !>   larger of turn_hysteresis of its range and a multiple of its quantum and noise;
   !> - a hold is a stretch where the control stays within a band of a few quanta (or noise
   !>   standard deviations) for longer than it takes the moving control to cross that band
   !>   hold_crossings times (an exactly constant piece when the control has no noise);
   !> - loading moves away from zero, unloading towards it, by the direction of the branch
   !>   between turns (not the local slope, which a quantised signal makes 0 or noisy);
   !>   reversal: within reversal_span of the range and reversal_branch of the branch's
   !>   travel from the last turn.
   !> Elastic and inelastic points come from the model (inelastic_points).
   pure subroutine point_classes(hist, t, cls, cycle)
      type(history_type), intent(in) :: hist
      real(dp), intent(in) :: t(:)
      integer, intent(out) :: cls(:), cycle(:)
      type(control_kinematics) :: kin
      real(dp) :: v, vnext
      integer :: i, k, nturn, dir
      logical :: near_turn
      kin = kinematics_of(hist)
      nturn = 0
      k = 1
      do i = 1, size(t)
         do while (nturn < size(kin%tturn))
            if (kin%tturn(nturn + 1) > t(i)) exit
            nturn = nturn + 1
         end do
         do while (k < size(hist%t) - 1)
            if (hist%t(k + 1) > t(i)) exit
            k = k + 1
         end do
         ! A cycle holds two turns; the rise before a cycle's first turn counts with the last
         cycle(i) = max(1, (nturn + 1)/2)
         v = hist%value_at(t(i))
         dir = kin%dir0*merge(1, -1, mod(nturn, 2) == 0)
         ! The reversal: near the last turn, against the whole range and the branch's own
         ! travel (a ratcheting test's short steps are not all reversal)
         near_turn = .false.
         if (nturn > 0) then
            vnext = hist%v(size(hist%v))
            if (nturn < size(kin%vturn)) vnext = kin%vturn(nturn + 1)
            near_turn = abs(v - kin%vturn(nturn)) < min(reversal_span*kin%range, &
                                                         reversal_branch*abs(vnext - kin%vturn(nturn)))
         end if
         if (kin%hold(k)) then
            cls(i) = class_hold
         else if (near_turn) then
            cls(i) = class_reversal
         else if (v*dir > 0.0_dp) then
            cls(i) = class_loading
         else
            cls(i) = class_unloading
         end if
      end do
   end subroutine point_classes

   !> Turns, holds and resolution of a control history (see point_classes)
   pure function kinematics_of(hist) result(kin)
      type(history_type), intent(in) :: hist
      type(control_kinematics) :: kin
      real(dp), allocatable :: dv(:), vs(:)
      real(dp) :: v, vext, hyst, travel, rate, tmin, lo, hi
      integer :: k, n, dir, it, a, b
      n = size(hist%v)
      kin%range = maxval(hist%v) - minval(hist%v)
      if (kin%range <= 0.0_dp) kin%range = 1.0_dp
      dv = abs(hist%v(2:n) - hist%v(1:n - 1))
      ! Quantum: the smallest step of a densely sampled control, when far below its range
      kin%quantum = 0.0_dp
      if (any(dv > 0.0_dp)) kin%quantum = minval(dv, dv > 0.0_dp)
      if (kin%quantum > quantum_fraction*kin%range) kin%quantum = 0.0_dp
      kin%noise = 0.0_dp
      if (n >= dense_corners) kin%noise = min(noise_sd(hist%v), quantum_fraction*kin%range)
      hyst = max(turn_hysteresis*kin%range, turn_quanta*kin%quantum, turn_noise*kin%noise)
      ! Turns: extremes of the control once it has come back by the hysteresis
      allocate (kin%tturn(0), kin%vturn(0))
      dir = 0
      kin%dir0 = 1
      vext = hist%v(1)
      it = 1
      travel = 0.0_dp
      do k = 2, n
         v = hist%v(k)
         if (dir == 0) then
            if (abs(v - vext) > hyst) then
               dir = merge(1, -1, v > vext)
               kin%dir0 = dir
               vext = v
               it = k
            end if
         else if (dir > 0 .and. v > vext .or. dir < 0 .and. v < vext) then
            vext = v
            it = k
         else if (abs(v - vext) > hyst) then
            kin%tturn = [kin%tturn, hist%t(it)]
            kin%vturn = [kin%vturn, vext]
            dir = -dir
            vext = v
            it = k
         end if
      end do
      ! Typical rate of the moving control: its travel between turns over the whole time
      dv = [hist%v(1), kin%vturn, hist%v(n)]
      travel = sum(abs(dv(2:) - dv(:size(dv) - 1)))
      rate = travel/max(hist%t(n) - hist%t(1), tiny(1.0_dp))
      kin%band = max(hold_quanta*kin%quantum, hold_noise*kin%noise)
      tmin = 0.0_dp
      if (kin%band > 0.0_dp) tmin = max(hold_crossings*kin%band/max(rate, tiny(1.0_dp)), &
                                        hold_samples*(hist%t(n) - hist%t(1))/(n - 1))
      ! Holds: the longest stretches from each corner within the band, if long enough
      allocate (vs(n))
      do k = 1, n
         vs(k) = sum(hist%v(max(1, k - hold_smooth):min(n, k + hold_smooth)))/ &
                 (min(n, k + hold_smooth) - max(1, k - hold_smooth) + 1)
      end do
      if (kin%band <= 0.0_dp) vs = hist%v
      allocate (kin%hold(max(n - 1, 1)))
      kin%hold = .false.
      a = 1
      do while (a < n)
         lo = vs(a)
         hi = lo
         b = a
         do while (b < n)
            lo = min(lo, vs(b + 1))
            hi = max(hi, vs(b + 1))
            if (hi - lo > kin%band) exit
            b = b + 1
         end do
         if (b > a .and. hist%t(b) - hist%t(a) >= tmin) then
            kin%hold(a:b - 1) = .true.
            a = b
         else
            a = a + 1
         end if
      end do
   end function kinematics_of

   !> Elastic or inelastic points from a simulation at the points: inelastic where the
   !> inelastic strain changes by more than inelastic_share of the total strain's change
   !> over a window of +- rate_window points (the window keeps a quantised measured strain
   !> from deciding), and by more than a floor; a hold (no total change) with relaxation or
   !> creep is inelastic. Points in time order, one test.
   pure function inelastic_points(eps, eps_in) result(inel)
      real(dp), intent(in) :: eps(:)      !< total strain, -
      real(dp), intent(in) :: eps_in(:)   !< the model's inelastic strain, -
      logical :: inel(size(eps))
      real(dp) :: a(size(eps)), b(size(eps)), floor
      integer :: i, n, i1, i2
      n = size(eps)
      inel = .false.
      if (n < 2) return
      do i = 1, n
         i1 = max(1, i - rate_window)
         i2 = min(n, i + rate_window)
         a(i) = abs(eps_in(i2) - eps_in(i1))
         b(i) = abs(eps(i2) - eps(i1))
      end do
      ! The floor: a share of the test's mean total change over a window, so that the
      ! round-off of an elastic stretch is not flow, and a slow relaxation is
      floor = inelastic_floor*sum(max(a, b))/n
      inel = a > inelastic_share*b .and. a > floor
   end function inelastic_points

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
      ! the noise explains; or, in a region too short for the runs test ever to reach z = -3
      ! (under 10 points: even one sign throughout gives z = -sqrt(n - 1)), a mean square
      ! residual of ten times the noise's or more (283 times, at 5 points, was called noise)
      st%structured = (st%z < -3.0_dp .and. st%ratio > 1.1_dp) .or. (st%n < 10 .and. st%ratio >= 10.0_dp)
   end function region_of

   !> Runs test on the signs of e, z = (runs - mean)/sd (negative: fewer runs than noise
   !> gives): the lower of the Wald-Wolfowitz z (given the counts of each sign) and the z
   !> against independent signs of even odds (runs - 1 binomial(n - 1, 1/2)). The first alone
   !> is blind to a residual of one sign (one run is all it allows: z 0 at 209 of 209 points);
   !> the second sees it (z = -sqrt(n - 1)).
   pure real(dp) function runs_z(e) result(z)
      real(dp), intent(in) :: e(:)
      real(dp) :: np, nm, n, mu, var
      integer :: i, runs
      z = 0.0_dp
      np = count(e > 0.0_dp)
      nm = count(e <= 0.0_dp)
      n = np + nm
      if (n < 2.0_dp) return
      runs = 1
      do i = 2, size(e)
         if ((e(i) > 0.0_dp) .neqv. (e(i - 1) > 0.0_dp)) runs = runs + 1
      end do
      z = (real(runs, dp) - 0.5_dp*(n + 1.0_dp))/sqrt(0.25_dp*(n - 1.0_dp))
      if (np < 1.0_dp .or. nm < 1.0_dp) return
      mu = 2.0_dp*np*nm/n + 1.0_dp
      var = (mu - 1.0_dp)*(mu - 2.0_dp)/(n - 1.0_dp)
      if (var <= 0.0_dp) return
      z = min(z, (real(runs, dp) - mu)/sqrt(var))
   end function runs_z

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

   !> Oscillation in the residual e (data - model, response unit, in time order) at the
   !> points in mask (the inelastic ones: serrated flow is a discontinuous yielding), over
   !> periods from 2 samples to max_period (give it well below a branch's length: a smooth
   !> gap repeated loop after loop has the loops' harmonics). The periodogram of the
   !> differenced residual (so the smooth gap does not leak into short periods), divided by
   !> the differencing's gain; each ordinate against the mean of its N neighbours but the
   !> adjacent ones (a red spectrum of structured misfit is smooth, a serration a narrow
   !> line). Under a locally flat spectrum the ordinates are exponential and an ordinate
   !> exceeds x times that mean with chance (1 + x/N)**(-N): p is K times the smallest such
   !> chance over the K ordinates.
   pure function serration_of(e, mask, max_period) result(st)
      real(dp), intent(in) :: e(:)
      logical, intent(in) :: mask(:)
      integer, intent(in), optional :: max_period
      type(serration_stat) :: st
      integer, parameter :: nb = 12      ! neighbours each side for the background
      real(dp), allocatable :: x(:), d(:), pg(:), ratio(:), nn(:), tc(:), ts(:)
      real(dp) :: c, s
      integer :: m, j, j0, j1, kk, jk, jmax, pmax, a, b
      pmax = serration_max_period
      if (present(max_period)) pmax = min(pmax, max_period)
      x = pack(e, mask)
      st%n = size(x)
      if (st%n < 32 .or. pmax < 3) return
      d = x(2:) - x(:st%n - 1)
      m = size(d)
      j0 = max(1, ceiling(real(m, dp)/pmax))
      j1 = (m - 1)/2
      if (j1 - j0 < 2*nb) return
      allocate (pg(max(1, j0 - nb):j1), ratio(j0:j1), nn(j0:j1), tc(0:m - 1), ts(0:m - 1))
      ! the m angles 2 pi jk/m once: every ordinate's terms are among them
      do jk = 0, m - 1
         call sincos_turn(real(jk, dp)/m, ts(jk), tc(jk))
      end do
      do j = lbound(pg, 1), j1
         c = 0.0_dp
         s = 0.0_dp
         jk = 0
         do kk = 1, m
            ! the angle 2 pi j kk/m in turns, reduced exactly first: jk = j kk mod m
            jk = jk + j
            if (jk >= m) jk = jk - m
            c = c + d(kk)*tc(jk)
            s = s + d(kk)*ts(jk)
         end do
         pg(j) = (c**2 + s**2)/m/(2.0_dp - 2.0_dp*tc(j))
      end do
      do j = j0, j1
         a = max(lbound(pg, 1), j - nb)
         b = min(j1, j + nb)
         nn(j) = real(max(j - 2 - a + 1, 0) + max(b - j - 2 + 1, 0), dp)
         ratio(j) = pg(j)/max((sum(pg(a:j - 2)) + sum(pg(j + 2:b)))/nn(j), tiny(1.0_dp))
         ! the chance, as -log
         ratio(j) = nn(j)*log_dp(1.0_dp + ratio(j)/nn(j))
      end do
      jmax = maxloc(ratio, 1) + j0 - 1
      kk = j1 - j0 + 1
      st%p = min(1.0_dp, kk*exp_dp(-ratio(jmax)))
      st%period = real(m, dp)/jmax
      ! A sinusoid of amplitude A gives an ordinate of about A**2 m/4
      st%amplitude = 2.0_dp*sqrt(pg(jmax)/m)
   end function serration_of

   !> Oscillation in the residual e at the points in mask, tested on their concatenation and
   !> on each contiguous run of 32 or more of them (a serration starts afresh on each branch
   !> of flow: across the runs its phase jumps and the concatenation's line spreads over as
   !> many ordinates as the runs are short); the smallest chance, times the number of tests
   !> made (Bonferroni), is p
   pure function serration_in_runs(e, mask, max_period) result(st)
      real(dp), intent(in) :: e(:)
      logical, intent(in) :: mask(:)
      integer, intent(in), optional :: max_period
      type(serration_stat) :: st
      type(serration_stat) :: sr
      integer :: a, b, ntest
      integer, allocatable :: starts(:), ends(:)
      st = serration_of(e, mask, max_period)
      allocate (starts(0), ends(0))
      a = 1
      do while (a <= size(mask))
         if (.not. mask(a)) then
            a = a + 1
            cycle
         end if
         b = a
         do while (b < size(mask))
            if (.not. mask(b + 1)) exit
            b = b + 1
         end do
         if (b - a + 1 >= 32) then
            starts = [starts, a]
            ends = [ends, b]
         end if
         a = b + 1
      end do
      ntest = 1 + size(starts)
      st%p = min(1.0_dp, ntest*st%p)
      do a = 1, size(starts)
         sr = serration_of(e(starts(a):ends(a)), mask(starts(a):ends(a)), max_period)
         sr%p = min(1.0_dp, ntest*sr%p)
         if (sr%p < st%p) st = sr
      end do
   end function serration_in_runs
end module usharp_regions
