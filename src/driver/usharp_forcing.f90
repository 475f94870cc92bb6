!> A measured control signal (strain, or stress) as the forcing of a simulation: its turning
!> points found with hysteresis, each branch between two of them smoothed (a discrete
!> smoothing spline whose residual matches the signal's noise) and interpolated by a cubic
!> spline, twice continuously differentiable inside a branch with a corner only at the
!> turning points. The integrators step across the samples with error control and stop at
!> the turning points only; the noise of the samples (quantisation, extensometer dips) no
!> longer reaches the simulated response as elastic spikes.
module usharp_forcing
   use usharp_kinds, only: dp
   use usharp_math, only: pow10_dp, cubic_piece, exp_dp, log_dp
   use usharp_error, only: error_type
   use usharp_history, only: history_type, history_from_points, spline_eval
   use usharp_sort, only: median, order_of
   implicit none
   private

   public :: measured_history, turning_points, turn_hysteresis, signal_resolution, smooth_branch, monotone
   public :: noise_sd, noise_lag_ratio

   !> A turning point is confirmed once the signal has come back from its extreme by more
   !> than turn_noise times its noise scale (see turn_hysteresis), and at least turn_fraction
   !> of its whole range. The noise sets it, not the range: a step test's first cycles are a
   !> tenth of its range or less. Inside the Alloy 617 strains' branches (cycles 1-2) the
   !> signal comes back by 7 quanta (7e-5) at most, at extensometer dips and serrations.
   real(dp), parameter :: turn_noise = 12.0_dp
   real(dp), parameter :: turn_fraction = 0.01_dp
   !> Default noise: the residual RMS left by the smoother, in units of the resolution of
   !> the recorded values (their smallest non-zero step); rounding to it alone leaves 0.29
   real(dp), parameter :: noise_in_steps = 1.0_dp
   !> Noise of unrounded values without scatter (a simulation's), as a share of their range:
   !> the smoother then passes through the samples to well within the accuracy of a fit
   real(dp), parameter :: unrounded_floor = 1.0e-7_dp
   !> Samples over which the smoother's residual RMS is bounded by the noise
   integer, parameter :: window = 10
   !> The spline of the forcing passes within knot_tol times the noise of every smoothed
   !> sample (see spline_knots). A knot, where the forcing's third derivative jumps, cuts
   !> the integrator's step short; at 1 the Alloy 617 tests (cycles 1-2) have 28-129 knots
   !> for their 234-1634 samples and take 1690 steps in all at rtol 1e-5, at 0.2 twice the
   !> knots and 1940 steps
   real(dp), parameter :: knot_tol = 1.0_dp
   !> A hold at a turning point: the samples about it within hold_noise times the noise scale
   !> (see turn_hysteresis) of its value, for at least hold_travel times the time the slower
   !> of the ramps beside it takes to cross that band as it meets it. It becomes a branch of
   !> its own, flat, with a corner at each end: a spline through a hold logged more slowly
   !> than the ramps (a sample every 20 s against every 0.5 s) had swung across it to half
   !> as much again as the peak strain, and a peak is compared where its hold starts. A
   !> rounded reversal is no hold: the Alloy 617 strains (cycles 1-2) stay within the band
   !> for at most 7.8 times their average ramp's crossing time
   real(dp), parameter :: hold_noise = 3.0_dp
   real(dp), parameter :: hold_travel = 20.0_dp
   !> ... the ramps' rates taken over their last approach_band band widths (see
   !> approach_rate): a sine rounded to 1e-5 at 1 % range had stayed within the band for 28
   !> times the time its average rate takes to cross it, and its peaks had been holds
   real(dp), parameter :: approach_band = 4.0_dp
   !> Rounding shows in at least this share of the second differences inside a signal's
   !> ramps (see rounding_shows): a noisy strain rounded to 1e-5 in most (the Alloy 617
   !> files), a dip of 5e-5 in a ramp logged on a grid of 1e-4 in 2 %, a regular sampling
   !> of steady ramps in none
   real(dp), parameter :: jitter_share = 0.01_dp
   !> Rounds of corners added where a branch's spline leaves its samples' range (at a
   !> branch's ends across steps longer than long_step times its fine sampling; see
   !> leaves_samples)
   integer, parameter :: max_passes = 4
   real(dp), parameter :: long_step = 10.0_dp
   !> ... by more than leave_tol times the noise
   real(dp), parameter :: leave_tol = 10.0_dp
   !> A step between a hold and its ramp longer than this many times the ramp's fine
   !> sampling holds the hold's start (or end): a regular logger's steps vary far less (a
   !> step of twice the ramp's, the hold's end inside it, had been left to the spline:
   !> 1.85e-4 off the command between the samples). Steps of the ramp's own length are
   !> left to it: a straight piece there starts the ramp from one noisy sample, not from
   !> the hold's level (5e-6 off along a whole ramp out of a hold at a noise of 3e-6)
   real(dp), parameter :: hold_step = 1.5_dp
   !> The noise of a signal is read from the residuals of local fits of rising degree (see
   !> signal_noise) up to degree 2 max_half - 1, each tried on at least fit_residuals samples
   integer, parameter :: max_half = 5, fit_residuals = 10
   !> A reversal between two samples is placed where the lines through this many samples
   !> either side of its turning point's sample meet (see reversals_between_samples)
   integer, parameter :: line_samples = 4

contains

   !> A history from measured samples (t in s, v strain or stress), as smooth forcing.
   !> Inside a branch the command moves one way: the samples are first made monotone (a dip,
   !> an extensometer's slip or noise, would load the model elastically back and forth) and
   !> then smoothed. noise: the residual RMS the smoother leaves in each branch (the unit of
   !> v); absent or negative: for values rounded to a resolution, that resolution (their
   !> smallest non-zero step), for unrounded values their own scatter (see noise_sd); 0: no
   !> smoothing, the samples are the corners of a piecewise-linear history (the integrators
   !> then stop at each of them).
   pure subroutine measured_history(t, v, control, hist, error, noise)
      real(dp), intent(in) :: t(:), v(:)
      integer, intent(in) :: control
      type(history_type), intent(out) :: hist
      type(error_type), allocatable, intent(out) :: error
      real(dp), intent(in), optional :: noise
      real(dp) :: sigma, scale, fine
      integer, allocatable :: stops(:), idx(:)
      real(dp), allocatable :: z(:), ends(:, :), mid(:), tk(:), vk(:), d2(:), mk(:)
      real(dp) :: rate
      integer :: j, a, b, i, first, pass
      logical, allocatable :: flat(:), leaves(:)
      integer, allocatable :: split(:)
      call history_from_points(t, v, control, hist, error)
      if (allocated(error)) return
      scale = noise_scale(t, v)
      sigma = -1.0_dp
      if (present(noise)) sigma = noise
      if (sigma < 0.0_dp) then
         if (quantum(v) > 0.0_dp) then
            sigma = noise_in_steps*signal_resolution(v)
         else
            ! Unrounded values (a simulation's, or noise without rounding): their smallest
            ! step is a sample's increment, not a resolution; their own scatter is the noise
            sigma = scale
         end if
      end if
      if (sigma <= 0.0_dp .or. size(t) < 3) return
      call turns_and_holds(t, v, scale, stops, flat)
      ! A branch's spline is checked between its samples too: where it leaves the range of
      ! two neighbouring samples by more than the knot tolerance (samples far apart, a hold
      ! or a pause logged slowly), those two samples become corners and the step between
      ! them a straight piece, and the branches are made again
      split = [integer ::]
      do pass = 1, max_passes
         if (allocated(z)) deallocate (z, ends, mid, tk, vk, d2, hist%kstops)
         allocate (z(size(v)), ends(2, size(stops) - 1), mid(size(stops)))
         do j = 1, size(stops) - 1
            a = stops(j)
            b = stops(j + 1)
            if (flat(j)) then
               z(a:b) = sum(v(a:b))/real(b - a + 1, dp)
            else
               z(a:b) = smooth_branch(t(a:b), monotone(v(a:b), v(b) >= v(a)), sigma)
            end if
            ends(:, j) = [z(a), z(b)]
         end do
         ! One value at each inner turning point, the mean of its two branches' ends (a hold's
         ! own value at its ends), reached by a linear correction of each branch (which leaves
         ! its curvature as it is)
         mid(1) = ends(1, 1)
         mid(size(stops)) = ends(2, size(stops) - 1)
         do j = 2, size(stops) - 1
            if (flat(j - 1)) then
               mid(j) = ends(2, j - 1)
            else if (flat(j)) then
               mid(j) = ends(1, j)
            else
               mid(j) = 0.5_dp*(ends(2, j - 1) + ends(1, j))
            end if
         end do
         allocate (tk(0), vk(0), d2(0), hist%kstops(size(stops)))
         hist%kstops(1) = 1
         do j = 1, size(stops) - 1
            a = stops(j)
            b = stops(j + 1)
            ! The shared samples hold the neighbours' values: restore this branch's own ends
            z(a) = ends(1, j)
            z(b) = ends(2, j)
            z(a:b) = z(a:b) + ((mid(j) - ends(1, j))*(t(b) - t(a:b)) + &
                               (mid(j + 1) - ends(2, j))*(t(a:b) - t(a)))/(t(b) - t(a))
            ! The branch's spline through a few of its smoothed samples; the samples take its
            ! values. Each branch's spline is natural (d2 = 0 at its ends), so the branches
            ! join at their shared knot
            call spline_knots(t(a:b), z(a:b), knot_tol*sigma, idx, mk)
            if (pass < max_passes) then
               fine = fine_step(t(a:b))
               leaves = leaves_samples(t(a:b), z(a:b), idx, mk, leave_tol*sigma, long_step*fine)
               ! A step next to a hold longer than hold_step times the branch's fine
               ! sampling: the hold began or ended inside it (a logger slowed for the hold),
               ! and the ramp runs straight to it (see hold_ends_between_samples)
               if (pass == 1 .and. .not. flat(j) .and. b - a >= 2) then
                  if (j > 1) then
                     if (flat(j - 1) .and. t(a + 1) - t(a) > hold_step*fine) leaves(1) = .true.
                  end if
                  if (j < size(flat)) then
                     if (flat(j + 1) .and. t(b) - t(b - 1) > hold_step*fine) leaves(size(leaves)) = .true.
                  end if
               end if
               do i = 1, size(leaves)
                  if (leaves(i)) split = [split, a - 1 + i, a + i]
               end do
            end if
            first = merge(1, 2, j == 1)
            tk = [tk, t(a - 1 + idx(first:))]
            vk = [vk, z(a - 1 + idx(first:))]
            d2 = [d2, mk(first:)]
            hist%kstops(j + 1) = size(tk)
            do i = a + 1, b - 1
               call spline_eval(tk, vk, d2, hist%kstops(j), hist%kstops(j + 1), t(i), z(i), rate)
            end do
         end do
         if (size(split) == 0) exit
         call add_corners(stops, flat, split)
         split = split(:0)
      end do
      hist%v = z
      hist%tk = tk
      hist%vk = vk
      hist%d2 = d2
      hist%stops = stops
      call approaches_into_holds(hist, flat, knot_tol*sigma)
      call reversals_between_samples(hist, flat, v, hold_noise*scale)
      call hold_ends_between_samples(hist, flat)
      call hold_ends_inside_steps(hist, flat, v, hold_noise*scale)
   end subroutine measured_history

   !> A hold that starts (or ends) inside a step of its ramp's own sampling: where the ramp's
   !> last (first, after the hold) line_samples samples lie on a line within band and the
   !> line meets the hold's level inside that step, away from the hold's sample (the line
   !> there off the level by more than band), a corner is added there and the ramp's spline
   !> ends (starts) at it. Left to the spline, the corner had been cut (a hold ending
   !> 0.25 s into a step of 0.5 s: 1e-4 strain off the command, 2.2 ksi of stress there);
   !> a straight piece from the ramp's last sample would start the ramp from one noisy
   !> sample, the line through several does not. A corner at the hold's sample is left to
   !> it: with a noise of 3e-6 the lines had met the level 5 ms after it, and the ramp's
   !> straight spline from there had lain 2.8e-6 off along its length (0.11 ksi). Runs
   !> after the other corners are placed:
   !> it finds its knots by their times.
   pure subroutine hold_ends_inside_steps(hist, flat, v, band)
      type(history_type), intent(inout) :: hist
      logical, intent(in) :: flat(:)  !< whether the branch from stops(j) to stops(j + 1) is a hold
      real(dp), intent(in) :: v(:)    !< the samples as measured
      real(dp), intent(in) :: band    !< how far a sample on the line may lie off it
      real(dp), allocatable :: tnew(:), vnew(:)
      integer, allocatable :: after(:), order(:), ramp(:)
      real(dp) :: b, slope, tc, level
      logical :: on
      integer :: j, s, e, i, n, ks, kn, k0, k1
      allocate (tnew(0), vnew(0), after(0), ramp(0))
      n = size(flat)
      do j = 1, n
         if (.not. flat(j)) cycle
         s = hist%stops(j)
         e = hist%stops(j + 1)
         level = hist%v(s)
         ! Into the hold: the ramp's last samples s - line_samples to s - 1
         if (j > 1) then
            if (.not. flat(j - 1) .and. s - hist%stops(j - 1) > line_samples) then
               call line_fit(hist%t(s - line_samples:s - 1) - hist%t(s), v(s - line_samples:s - 1), band, b, slope, on)
               if (on .and. abs(b - level) > band .and. regular(s - line_samples, s)) then
                  tc = crossing(hist%t(s), b, slope, hist%t(s - 1), hist%t(s))
                  ks = findloc(hist%tk, hist%t(s), 1)
                  if (tc > hist%t(s - 1) .and. ks > 1) then
                     tnew = [tnew, tc]
                     vnew = [vnew, level]
                     after = [after, ks - 1]
                     ramp = [ramp, -1]
                  end if
               end if
            end if
         end if
         ! Out of the hold: the ramp's first samples e + 1 to e + line_samples
         if (j < n) then
            if (.not. flat(j + 1) .and. hist%stops(j + 2) - e > line_samples) then
               call line_fit(hist%t(e + 1:e + line_samples) - hist%t(e), v(e + 1:e + line_samples), band, b, slope, on)
               if (on .and. abs(b - level) > band .and. regular(e, e + line_samples)) then
                  tc = crossing(hist%t(e), b, slope, hist%t(e), hist%t(e + 1))
                  ks = findloc(hist%tk, hist%t(e), 1)
                  if (tc > hist%t(e) .and. ks > 0) then
                     tnew = [tnew, tc]
                     vnew = [vnew, hist%v(e)]
                     after = [after, ks]
                     ramp = [ramp, 1]
                  end if
               end if
            end if
         end if
      end do
      if (size(tnew) == 0) return
      order = order_of(tnew)
      call insert_knots(hist, tnew(order), vnew(order), after(order))
      ! The ramp's spline made again to end (start) at the new corner, its samples on it
      do i = 1, size(order)
         kn = findloc(hist%tk, tnew(order(i)), 1)
         if (ramp(order(i)) < 0) then
            k0 = hist%kstops(count(hist%kstops < kn))
            k1 = kn
         else
            k0 = kn
            k1 = hist%kstops(count(hist%kstops <= kn) + 1)
         end if
         hist%d2(k0:k1) = natural_spline(hist%tk(k0:k1), hist%vk(k0:k1))
         do s = 1, size(hist%t)
            if (hist%t(s) > hist%tk(k0) .and. hist%t(s) < hist%tk(k1)) &
               call spline_eval(hist%tk, hist%vk, hist%d2, k0, k1, hist%t(s), hist%v(s), b)
         end do
      end do
   contains
      !> Whether the steps of samples i0 to i1 are alike (none longer than hold_step times
      !> their fine sampling): a step of the ramp's own sampling, not a hold logged slowly
      pure logical function regular(i0, i1)
         integer, intent(in) :: i0, i1
         regular = maxval(hist%t(i0 + 1:i1) - hist%t(i0:i1 - 1)) <= hold_step*fine_step(hist%t(i0:i1))
      end function regular
      !> Where the line of value b0 at time t0 and slope sl meets the level: inside (lo, hi),
      !> away from both by a millionth of the step, or -huge where it does not
      pure real(dp) function crossing(t0, b0, sl, lo, hi) result(tx)
         real(dp), intent(in) :: t0, b0, sl, lo, hi
         real(dp) :: gap
         tx = -huge(1.0_dp)
         if (.not. abs(sl) > 0.0_dp) return
         gap = 1.0e-6_dp*(hi - lo)
         if (.not. (t0 + (level - b0)/sl > lo + gap .and. t0 + (level - b0)/sl < hi - gap)) return
         tx = t0 + (level - b0)/sl
      end function crossing
   end subroutine hold_ends_inside_steps

   !> A sharp reversal between two samples: the ramps on either side are straight (their
   !> last line_samples samples each on a line within band), the turning point's sample lies
   !> on the line of one of them but not of the other, and the two lines meet inside its
   !> step to the other side, beyond it. The corner (the knot of the turning point) moves to
   !> where the lines meet, and the two branches' splines are made again through it: the
   !> sample at the turn had cut the peak short (a triangle whose minimum fell 0.1 s before a
   !> sample, 0.5 s apart, had been 1.5e-4 short of it, 2.2 ksi of stress there). A rounded
   !> reversal (a servo's), one at a sample, or one across a step longer than hold_step
   !> times the ramps' (a logger that records on a change of the strain, the Alloy 617
   !> files' 0.21 s at a reversal against 0.03-0.05 s on the ramps: the strain dwelt there,
   !> and a corner where the lines meet, beyond the peak sample, had raised the
   !> objective from 496.06 to 529.26) is left as it is.
   pure subroutine reversals_between_samples(hist, flat, v, band)
      type(history_type), intent(inout) :: hist
      logical, intent(in) :: flat(:)  !< whether branch j is a hold
      real(dp), intent(in) :: v(:)    !< the samples as measured
      real(dp), intent(in) :: band    !< how far a sample on a line may lie off it
      real(dp) :: b(2), sl(2), tc, vc, val, rate
      logical :: on(2)
      integer :: j, k, kk, i, side
      do j = 2, size(hist%stops) - 1
         if (flat(j - 1) .or. flat(j)) cycle
         k = hist%stops(j)
         if (k - hist%stops(j - 1) < line_samples .or. hist%stops(j + 1) - k < line_samples) cycle
         ! The lines before and after (value b at the turn's time, slope sl)
         call line_fit(hist%t(k - line_samples:k - 1) - hist%t(k), v(k - line_samples:k - 1), band, b(1), sl(1), on(1))
         call line_fit(hist%t(k + 1:k + line_samples) - hist%t(k), v(k + 1:k + line_samples), band, b(2), sl(2), on(2))
         if (.not. (on(1) .and. on(2))) cycle
         if (.not. abs(sl(1) - sl(2)) > 0.0_dp) cycle
         on = abs(v(k) - b) <= band
         if (on(1) .eqv. on(2)) cycle
         ! (the turn's sample on the line after: the lines meet in the step before it)
         side = merge(-1, 1, on(2))
         tc = (b(2) - b(1))/(sl(1) - sl(2))
         vc = b(1) + sl(1)*tc
         tc = hist%t(k) + tc
         if (.not. (side*(tc - hist%t(k)) > 0.0_dp .and. side*(hist%t(k + side) - tc) > 0.0_dp)) cycle
         ! (a logger that records on a change of the strain slows where it dwells: a step
         ! across the turn longer than its ramps' lets it be rounded)
         if (abs(hist%t(k + side) - hist%t(k)) > hold_step*fine_step(hist%t(k - line_samples:k + line_samples))) cycle
         ! (beyond the turn's sample, in the direction of the branch before it)
         if (.not. (vc - v(k))*sign(1.0_dp, v(k) - v(hist%stops(j - 1))) > band) cycle
         kk = hist%kstops(j)
         hist%tk(kk) = tc
         hist%vk(kk) = vc
         do i = j - 1, j
            associate (k0 => hist%kstops(i), k1 => hist%kstops(i + 1))
               hist%d2(k0:k1) = natural_spline(hist%tk(k0:k1), hist%vk(k0:k1))
            end associate
         end do
         ! The samples of both branches take the splines' values
         do i = hist%stops(j - 1) + 1, hist%stops(j + 1) - 1
            associate (ks => hist%kstops)
               if (hist%t(i) < tc) then
                  call spline_eval(hist%tk, hist%vk, hist%d2, ks(j - 1), ks(j), hist%t(i), val, rate)
               else
                  call spline_eval(hist%tk, hist%vk, hist%d2, ks(j), ks(j + 1), hist%t(i), val, rate)
               end if
            end associate
            hist%v(i) = val
         end do
      end do
   end subroutine reversals_between_samples

   !> The least-squares line through (t, v): its value b at t = 0 and its slope, and whether
   !> every sample lies within band of it
   pure subroutine line_fit(t, v, band, b, slope, on)
      real(dp), intent(in) :: t(:), v(:), band
      real(dp), intent(out) :: b, slope
      logical, intent(out) :: on
      real(dp) :: tm, vm
      tm = sum(t)/real(size(t), dp)
      vm = sum(v)/real(size(v), dp)
      slope = sum((t - tm)*(v - vm))/sum((t - tm)**2)
      b = vm - slope*tm
      on = all(abs(v - b - slope*t) <= band)
   end subroutine line_fit

   !> A controller's approach to a hold logged slowly: between the ramp's last sample and the
   !> hold's first (its first within the hold's band) lie samples logged at the hold's pace,
   !> short of the level by less and less, each a corner of a straight piece so far (a PID
   !> that slows over the last few per cent of a ramp, its approach caught by a sample 20 s
   !> on, 3.5e-7 short, 3.3e-4 off the approach's strain for 20 s and 2 ksi of stress). The
   !> command approaches the level as a first-order system does: the shortfall decays
   !> exponentially from the ramp's last sample, through each of these samples (its time
   !> constant between two of them read from their shortfalls), to the hold. The pieces
   !> become one branch of a few cubic pieces along that exponential; its samples are no
   !> longer corners. Where the samples do not close in on the level monotonically, or the
   !> approach would leave the ramp faster than the ramp ran (a hold that drifts after the
   !> ramp ran into it), it is left as it is.
   pure subroutine approaches_into_holds(hist, flat, tol)
      type(history_type), intent(inout) :: hist
      logical, allocatable, intent(inout) :: flat(:)  !< whether branch j is a hold
      real(dp), intent(in) :: tol   !< the forcing's tolerance (the unit of the signal)
      real(dp), allocatable :: tn(:), vn(:), d2n(:), tf(:)
      real(dp) :: level, sgn, fine, u, rate
      integer :: j, m, r, s, k0, k1, i
      ! (from the last branch back, so that a merge leaves the branches before it as they are)
      j = size(flat) + 1
      do while (j > 3)
         j = j - 1
         if (.not. flat(j)) cycle
         ! Back from the hold: the straight pieces of one step each, logged slowly
         m = 0
         do i = j - 1, 2, -1
            if (flat(i) .or. hist%stops(i + 1) - hist%stops(i) /= 1) exit
            m = m + 1
         end do
         if (m < 2) cycle
         if (flat(j - m - 1)) cycle
         r = hist%stops(j - m)
         s = hist%stops(j)
         tf = hist%t(hist%stops(j - m - 1):r)
         if (size(tf) < 2) cycle
         fine = fine_step(tf)
         if (minval(hist%t(r + 1:s) - hist%t(r:s - 1)) <= hold_step*fine) cycle
         k0 = hist%kstops(j - m)
         k1 = hist%kstops(j)
         ! (one knot per sample between: no corner added inside these pieces)
         if (k1 - k0 /= m) cycle
         level = hist%vk(k1)
         sgn = sign(1.0_dp, level - hist%v(r))
         ! (the ramp's rate at its last sample)
         call cubic_piece(hist%tk, hist%vk, hist%d2, k0 - 1, hist%tk(k0), u, rate)
         call approach_knots(hist%t(r:s), sgn*(level - hist%v(r:s)), tol, abs(rate), tn, vn, d2n)
         if (size(tn) == 0) cycle
         ! (the approach becomes branch j - m; the next hold to look at lies before it)
         j = j - m
         vn = level - sgn*vn
         d2n = -sgn*d2n
         hist%tk = [hist%tk(:k0), tn, hist%tk(k1:)]
         hist%vk = [hist%vk(:k0), vn, hist%vk(k1:)]
         hist%d2 = [hist%d2(:k0), d2n, hist%d2(k1:)]
         hist%kstops = [hist%kstops(:j), hist%kstops(j + m:) + size(tn) - m + 1]
         hist%stops = [hist%stops(:j), hist%stops(j + m:)]
         flat = [flat(:j), flat(j + m:)]
      end do
   end subroutine approaches_into_holds

   !> The inner knots (t, shortfall d, its second derivative d2) of a first-order approach
   !> through the shortfalls d(:) of samples at times t(:): d(1) the ramp's last sample's,
   !> d(n) the hold's first (taken as none); between two samples the shortfall decays
   !> exponentially, its time constant read from their ratio, past the last sample short
   !> of the level at that sample's. Knots every half time constant (a cubic that matches
   !> an exponential's value and second derivative at both ends is within 1e-3 of its
   !> shortfall there), closer at the start, where the ramp's end keeps d2 = 0, until the
   !> shortfall is within tol. None where the shortfalls do not fall from one sample to the
   !> next, or where the approach would leave the ramp faster than fastest (per s).
   pure subroutine approach_knots(t, d, tol, fastest, tk, dk, d2k)
      real(dp), intent(in) :: t(:), d(:), tol, fastest
      real(dp), allocatable, intent(out) :: tk(:), dk(:), d2k(:)
      real(dp) :: tau, h, x, a, left
      integer :: n, i, p
      n = size(t)
      allocate (tk(0), dk(0), d2k(0))
      if (n < 3) return
      if (.not. all(d(2:n - 1) > 0.0_dp .and. d(2:n - 1) < d(1:n - 2))) return
      tau = 0.0_dp
      left = 0.0_dp
      do i = 1, n - 1
         ! (the last step, into the hold, at the time constant before it)
         if (i < n - 1) tau = (t(i + 1) - t(i))/log_dp(d(i)/d(i + 1))
         if (i == 1 .and. d(1)/tau > fastest) return
         a = d(i)
         if (i > 1) then
            tk = [tk, t(i)]
            dk = [dk, a]
            ! (the mean of the two exponentials' second derivatives at their shared sample)
            d2k = [d2k, 0.5_dp*(left + a/tau**2)]
         end if
         ! knots inside: at tau/8, tau/4, tau/2, then every tau/2
         x = 0.0_dp
         h = merge(0.125_dp*tau, 0.5_dp*tau, i == 1)
         do p = 1, 100000
            x = x + h
            if (x > t(i + 1) - t(i) - 0.25_dp*tau) exit
            if (i == n - 1 .and. a*exp_dp(-x/tau) < tol) exit
            tk = [tk, t(i) + x]
            dk = [dk, a*exp_dp(-x/tau)]
            d2k = [d2k, a*exp_dp(-x/tau)/tau**2]
            h = min(2.0_dp*h, 0.5_dp*tau)
         end do
         left = d(i + 1)/tau**2
      end do
   end subroutine approach_knots

   !> A hold whose start (or end) falls between two samples far apart (a ramp logged every
   !> 0.5 s into a hold logged every 20 s, its level reached 0.1 s after the ramp's last
   !> sample) is joined to its ramp by a straight piece across that step (see
   !> leaves_samples): the ramp would run on at a fraction of its rate to the hold's first
   !> sample, 15 s late, and the hold relax from there. The command runs at its rate up to
   !> the level: a corner is added where the ramp's rate at its last sample (first, after a
   !> hold) meets the hold's level, inside that step, and the forcing holds from there. The
   !> samples and their corners (hist%stops) stay as they are; the new corners are knots
   !> (hist%kstops) between samples.
   pure subroutine hold_ends_between_samples(hist, flat)
      type(history_type), intent(inout) :: hist
      logical, intent(in) :: flat(:)  !< whether the branch from stops(j) to stops(j + 1) is a hold
      real(dp), allocatable :: tnew(:), vnew(:)
      integer, allocatable :: after(:), order(:)
      real(dp) :: ts, u, rate
      integer :: j, nb, kr, k0, k1
      nb = size(flat)
      allocate (tnew(0), vnew(0), after(0))
      do j = 1, nb
         if (.not. flat(j)) cycle
         associate (tk => hist%tk, vk => hist%vk, d2 => hist%d2, ks => hist%kstops, st => hist%stops)
            ! Into the hold: a ramp (j - 2), then a straight piece of one step (j - 1)
            if (j >= 3) then
               if (.not. flat(j - 2) .and. .not. flat(j - 1) .and. st(j) - st(j - 1) == 1 .and. &
                   ks(j) - ks(j - 1) == 1) then
                  k0 = ks(j - 1)
                  kr = ks(j - 1) - 1     ! the ramp's last piece
                  call cubic_piece(tk, vk, d2, kr, tk(k0), u, rate)
                  ts = meet(tk(k0), vk(k0), rate, vk(ks(j)), tk(k0), tk(ks(j)))
                  if (ts > tk(k0)) then
                     tnew = [tnew, ts]
                     vnew = [vnew, vk(ks(j))]
                     after = [after, k0]
                  end if
               end if
            end if
            ! Out of the hold: a straight piece of one step (j + 1), then a ramp (j + 2)
            if (j + 2 <= nb) then
               if (.not. flat(j + 2) .and. .not. flat(j + 1) .and. st(j + 2) - st(j + 1) == 1 .and. &
                   ks(j + 2) - ks(j + 1) == 1) then
                  k1 = ks(j + 2)
                  call cubic_piece(tk, vk, d2, k1, tk(k1), u, rate)
                  ts = meet(tk(k1), vk(k1), rate, vk(ks(j + 1)), tk(ks(j + 1)), tk(k1))
                  if (ts > tk(ks(j + 1))) then
                     tnew = [tnew, ts]
                     vnew = [vnew, vk(ks(j + 1))]
                     after = [after, ks(j + 1)]
                  end if
               end if
            end if
         end associate
      end do
      if (size(tnew) == 0) return
      ! Each new knot after knot after(i), a corner of its own
      order = order_of(tnew)
      tnew = tnew(order)
      vnew = vnew(order)
      after = after(order)
      call insert_knots(hist, tnew, vnew, after)
   contains
      !> Where a ramp through (t0, v0) at rate meets level: inside (lo, hi), away from both by
      !> a millionth of the step, or -huge where it does not
      pure real(dp) function meet(t0, v0, rate, level, lo, hi) result(ts)
         real(dp), intent(in) :: t0, v0, rate, level, lo, hi
         real(dp) :: gap
         ts = -huge(1.0_dp)
         if (.not. abs(rate) > 0.0_dp) return
         gap = 1.0e-6_dp*(hi - lo)
         if (.not. ((level - v0)/rate > lo - t0 + gap .and. (level - v0)/rate < hi - t0 - gap)) return
         ts = t0 + (level - v0)/rate
      end function meet
   end subroutine hold_ends_between_samples

   !> Knots (t, v), with zero second derivative, into a smooth history after its knots
   !> after(:) (ascending), each a corner (kstops) of its own
   pure subroutine insert_knots(hist, t, v, after)
      type(history_type), intent(inout) :: hist
      real(dp), intent(in) :: t(:), v(:)
      integer, intent(in) :: after(:)
      real(dp), allocatable :: tk(:), vk(:), d2(:)
      integer, allocatable :: knew(:), old(:), ks(:)
      integer :: i, k, n
      n = size(hist%tk)
      ! Knot k moves on by the new knots before it; new knot i lands after knot after(i)
      ! and the i - 1 new ones before it
      old = [(k + count(after < k), k=1, n)]
      knew = [(after(i) + i, i=1, size(t))]
      allocate (tk(n + size(t)), vk(n + size(t)), d2(n + size(t)))
      tk(old) = hist%tk
      vk(old) = hist%vk
      d2(old) = hist%d2
      tk(knew) = t
      vk(knew) = v
      d2(knew) = 0.0_dp
      ks = [old(hist%kstops), knew]
      ks = ks(order_of(real(ks, dp)))
      hist%tk = tk
      hist%vk = vk
      hist%d2 = d2
      hist%kstops = ks
   end subroutine insert_knots

   !> Per interval between neighbouring samples (t, z), whether the spline through the knots
   !> idx with second derivatives m leaves the range of its two samples by more than tol
   !> (looked at 7 times inside each interval): every interval inside the branch (a ramp
   !> logged every 0.05 s into a relaxation hold logged every 0.5 s, ten times as long, had
   !> swung by 0.3 ksi of stress there), and at its two ends those longer than long (s;
   !> long_step times the branch's fine sampling: next to a turning point the extreme of a
   !> reversal between samples lies beyond the two, and the spline may follow it)
   pure function leaves_samples(t, z, idx, m, tol, long) result(flag)
      real(dp), intent(in) :: t(:), z(:), m(:), tol, long
      integer, intent(in) :: idx(:)
      logical :: flag(size(t) - 1)
      real(dp) :: tk(size(idx)), zk(size(idx)), u, du, lo, hi
      integer :: i, k, p
      tk = t(idx)
      zk = z(idx)
      flag = .false.
      if (size(t) < 3) return
      p = 1
      do i = 1, size(t) - 1
         do while (p < size(idx) - 1)
            if (idx(p + 1) > i) exit
            p = p + 1
         end do
         ! (a reversal between two samples puts the extreme beyond the pair next to the
         ! turning point: the branch's end steps are looked at only when long)
         if ((i == 1 .or. i == size(t) - 1) .and. t(i + 1) - t(i) <= long) cycle
         lo = min(z(i), z(i + 1)) - tol
         hi = max(z(i), z(i + 1)) + tol
         do k = 1, 7
            call cubic_piece(tk, zk, m, p, t(i) + (t(i + 1) - t(i))*real(k, dp)/8.0_dp, u, du)
            if (u < lo .or. u > hi) then
               flag(i) = .true.
               exit
            end if
         end do
      end do
   end function leaves_samples

   !> A branch's fine sampling (s): its steps' tenth percentile (a hold logged slowly holds
   !> most of a relaxation branch's samples)
   pure real(dp) function fine_step(t) result(dt)
      real(dp), intent(in) :: t(:)   !< its sample times, s, at least two
      real(dp), allocatable :: steps(:)
      steps = t(2:) - t(:size(t) - 1)
      steps = steps(order_of(steps))
      dt = steps(max(1, (size(steps) + 5)/10))
   end function fine_step

   !> New corners (sample indices) into stops, in order, each branch they split keeping its
   !> kind (flat: a hold) for its parts but the straight pieces between two new corners of a
   !> pair (a hold between two such pieces, each of its ends a new corner, stays a hold)
   pure subroutine add_corners(stops, flat, new)
      integer, allocatable, intent(inout) :: stops(:)
      logical, allocatable, intent(inout) :: flat(:)
      !> pairs of neighbouring samples, the ends of a straight piece each
      integer, intent(in) :: new(:)
      integer, allocatable :: all(:)
      logical, allocatable :: f(:)
      integer :: j, k
      all = stops
      do k = 1, size(new)
         if (.not. any(all == new(k))) all = [all, new(k)]
      end do
      all = all(order_of(real(all, dp)))
      allocate (f(size(all) - 1))
      do j = 1, size(all) - 1
         ! the branch of the old stops that holds this piece
         k = count(stops <= all(j))
         f(j) = flat(k) .and. .not. any(new(1::2) == all(j) .and. new(2::2) == all(j + 1))
      end do
      stops = all
      flat = f
   end subroutine add_corners

   !> The corners of a measured signal v at times t: its turning points (see turning_points)
   !> and, where a turning point lies in a hold (see hold_noise), the hold's first and last
   !> samples in its place; flat(j) whether the branch from stops(j) to stops(j + 1) is a hold
   pure subroutine turns_and_holds(t, v, scale, stops, flat)
      real(dp), intent(in) :: t(:), v(:)
      real(dp), intent(in) :: scale   !< the noise scale of v (see noise_scale)
      integer, allocatable, intent(out) :: stops(:)
      logical, allocatable, intent(out) :: flat(:)
      integer, allocatable :: turns(:)
      integer :: buf(2*size(v)), j, n, s, e, k
      logical :: held(2*size(v))
      real(dp) :: tol, rate, level
      turns = turning_points(v, turn_hysteresis(v, scale))
      tol = hold_noise*scale
      n = 1
      buf(1) = turns(1)
      held = .false.
      ! A hold at the start (a test that rests before its first ramp): the samples from the
      ! first within the band of their level, for as long as at a turning point, become a
      ! flat branch, so the ramp leaves it where its own line meets the level (see
      ! hold_ends_between_samples, hold_ends_inside_steps); one spline from the first sample
      ! had cut that corner, 1.0e-4 off the command and 2.3 ksi of stress there
      call walk(v, 1, 0, turns(2), v(1), 2.0_dp*tol, s, e)
      call walk(v, 1, 0, turns(2), median(v(s:e)), tol, s, e)
      level = median(v(s:e))
      rate = approach_rate(t, v, e, turns(2), level, approach_band*tol)
      if (e > 1 .and. (t(e) - t(1))*rate >= hold_travel*tol) then
         n = 2
         buf(2) = e
         held(1) = .true.
      end if
      do j = 2, size(turns) - 1
         k = turns(j)
         ! The extreme of a noisy hold is its highest sample, not its level: the samples
         ! within twice the band of it give the level (their median), the band about
         ! that the hold
         call walk(v, k, turns(j - 1), turns(j + 1), v(k), 2.0_dp*tol, s, e)
         call walk(v, k, turns(j - 1), turns(j + 1), median(v(s:e)), tol, s, e)
         ! (the rates, per s, at which the ramps before and after meet the band)
         level = median(v(s:e))
         rate = min(approach_rate(t, v, s, turns(j - 1), level, approach_band*tol), &
                    approach_rate(t, v, e, turns(j + 1), level, approach_band*tol))
         if (e > s .and. (t(e) - t(s))*rate >= hold_travel*tol) then
            buf(n + 1:n + 2) = [s, e]
            held(n + 1) = .true.
            n = n + 2
         else
            n = n + 1
            buf(n) = k
         end if
      end do
      if (size(turns) > 1) then
         ! The signal's end in a hold logged more slowly than the ramp into it (a test
         ! ending on a hold after its last turning point, its first sample a step of more
         ! than hold_step times the ramp's fine sampling after the ramp's last): the hold's
         ! first sample becomes a corner and the hold a flat branch, as at a turning point
         ! but with the ramp before it alone (from the last corner), so the ramp runs at its
         ! rate into it (see hold_ends_between_samples). Logged as the ramp, the branch runs
         ! on to the end as before, where a servo's rounded approach to the level is
         ! followed (a corner at its first sample within the band had laid the ramp before
         ! it 3e-5 off); so too after an overshoot beyond the band that settles back
         k = turns(size(turns))
         call walk(v, k, buf(n), k + 1, v(k), 2.0_dp*tol, s, e)
         call walk(v, k, buf(n), k + 1, median(v(s:e)), tol, s, e)
         level = median(v(s:e))
         rate = 0.0_dp
         if (s - buf(n) >= 2) then
            if (t(s) - t(s - 1) > hold_step*fine_step(t(buf(n):s)) .and. &
                .not. any((v(buf(n) + 1:s - 1) - level)*sign(1.0_dp, level - v(buf(n))) > tol)) &
               rate = approach_rate(t, v, s, buf(n), level, approach_band*tol)
         end if
         if (e > s .and. (t(e) - t(s))*rate >= hold_travel*tol) then
            n = n + 1
            buf(n) = s
            held(n) = .true.
         end if
         n = n + 1
         buf(n) = k
      end if
      stops = buf(:n)
      flat = held(:n - 1)
   end subroutine turns_and_holds

   !> The rate (per s) at which the signal v reaches sample k from the side of sample far:
   !> over its samples from the last that lies farther than reach from level (far if none)
   !> to k. A ramp into a hold keeps its rate up to the hold; a rounded top slows as it
   !> nears (a parabola crosses the band's width beyond it in under a third of the time it
   !> stays within it)
   pure real(dp) function approach_rate(t, v, k, far, level, reach) result(rate)
      real(dp), intent(in) :: t(:), v(:), level, reach
      integer, intent(in) :: k, far
      integer :: i, step
      step = merge(-1, 1, far < k)
      i = k
      do while (i /= far)
         i = i + step
         if (abs(v(i) - level) > reach) exit
      end do
      rate = 0.0_dp
      if (i /= k) rate = abs(v(i) - v(k))/abs(t(i) - t(k))
   end function approach_rate

   !> s, e: the first and last samples about index k (strictly between lo and hi) within band
   !> of level, contiguous with k
   pure subroutine walk(v, k, lo, hi, level, band, s, e)
      real(dp), intent(in) :: v(:), level, band
      integer, intent(in) :: k, lo, hi
      integer, intent(out) :: s, e
      s = k
      do while (s - 1 > lo)
         if (abs(v(s - 1) - level) > band) exit
         s = s - 1
      end do
      e = k
      do while (e + 1 < hi)
         if (abs(v(e + 1) - level) > band) exit
         e = e + 1
      end do
   end subroutine walk

   !> The knots (indices idx into t, the first and the last included) of a natural cubic
   !> spline through (t(idx), z(idx)) that passes within tol of every z, and its second
   !> derivatives m there: knots are added, in each interval between knots at its sample of
   !> largest deviation, until none deviates by more than tol. A straight ramp needs its two
   !> ends only; the knots gather where the signal bends.
   pure subroutine spline_knots(t, z, tol, idx, m)
      real(dp), intent(in) :: t(:), z(:), tol
      integer, allocatable, intent(out) :: idx(:)
      real(dp), allocatable, intent(out) :: m(:)
      real(dp), allocatable :: tk(:), zk(:)
      integer :: add(size(t)), na, j, i, worst, n
      real(dp) :: dev, most, s, rate
      n = size(t)
      idx = [1, n]
      if (n <= 2) idx = [(i, i=1, n)]
      do
         tk = t(idx)
         zk = z(idx)
         m = natural_spline(tk, zk)
         na = 0
         do j = 1, size(idx) - 1
            most = tol
            worst = 0
            do i = idx(j) + 1, idx(j + 1) - 1
               call cubic_piece(tk, zk, m, j, t(i), s, rate)
               dev = abs(s - z(i))
               if (dev > most) then
                  most = dev
                  worst = i
               end if
            end do
            if (worst > 0) then
               na = na + 1
               add(na) = worst
            end if
         end do
         if (na == 0) exit
         idx = merge_sorted(idx, add(:na))
      end do
   end subroutine spline_knots

   !> The union of two increasing index lists that share no entry, in increasing order
   pure function merge_sorted(p, q) result(r)
      integer, intent(in) :: p(:), q(:)
      integer :: r(size(p) + size(q))
      integer :: i, j, k
      i = 1
      j = 1
      do k = 1, size(r)
         if (j > size(q)) then
            r(k) = p(i)
            i = i + 1
         else if (i > size(p)) then
            r(k) = q(j)
            j = j + 1
         else if (p(i) < q(j)) then
            r(k) = p(i)
            i = i + 1
         else
            r(k) = q(j)
            j = j + 1
         end if
      end do
   end function merge_sorted

   !> Indices of the turning points of v (with the first and the last sample): an extreme
   !> counts once the signal has come back from it by more than delta
   pure function turning_points(v, delta) result(idx)
      real(dp), intent(in) :: v(:), delta
      integer, allocatable :: idx(:)
      integer :: buf(size(v)), n, k, ext, dir
      n = 1
      buf(1) = 1
      dir = 0
      ext = 1
      do k = 2, size(v)
         select case (dir)
         case (0)
            ! Direction not yet known: follow both extremes from the start
            if (v(k) - v(1) > delta) then
               dir = 1
               ext = maxloc(v(:k), 1)
            else if (v(1) - v(k) > delta) then
               dir = -1
               ext = minloc(v(:k), 1)
            end if
         case (1)
            if (v(k) >= v(ext)) then
               ext = k
            else if (v(ext) - v(k) > delta) then
               n = n + 1
               buf(n) = ext
               dir = -1
               ext = k
            end if
         case default
            if (v(k) <= v(ext)) then
               ext = k
            else if (v(k) - v(ext) > delta) then
               n = n + 1
               buf(n) = ext
               dir = 1
               ext = k
            end if
         end select
      end do
      if (buf(n) /= size(v)) then
         n = n + 1
         buf(n) = size(v)
      end if
      idx = buf(:n)
   end function turning_points

   !> The least-squares monotone (rising, or falling) fit of y: pool adjacent violators
   pure function monotone(y, rising) result(z)
      real(dp), intent(in) :: y(:)
      logical, intent(in) :: rising
      real(dp) :: z(size(y))
      real(dp) :: val(size(y)), s
      integer :: cnt(size(y)), nb, k, i
      s = merge(1.0_dp, -1.0_dp, rising)
      nb = 0
      do k = 1, size(y)
         nb = nb + 1
         val(nb) = s*y(k)
         cnt(nb) = 1
         do while (nb > 1)
            if (val(nb - 1) <= val(nb)) exit
            val(nb - 1) = (val(nb - 1)*cnt(nb - 1) + val(nb)*cnt(nb))/real(cnt(nb - 1) + cnt(nb), dp)
            cnt(nb - 1) = cnt(nb - 1) + cnt(nb)
            nb = nb - 1
         end do
      end do
      k = 0
      do i = 1, nb
         z(k + 1:k + cnt(i)) = s*val(i)
         k = k + cnt(i)
      end do
   end function monotone

   !> The hysteresis of the turning points of v (its unit): turn_noise times its noise scale
   !> (see noise_scale), at least turn_fraction of its range
   pure real(dp) function turn_hysteresis(v, scale) result(delta)
      real(dp), intent(in) :: v(:)
      real(dp), intent(in) :: scale   !< the noise scale of v
      delta = max(turn_noise*scale, turn_fraction*(maxval(v) - minval(v)))
   end function turn_hysteresis

   !> The noise scale of a measured signal v at times t (its unit), for its turning points,
   !> its holds and, unrounded, its smoothing: the larger of its quantum (see quantum) and
   !> its noise (see signal_noise), and at least unrounded_floor of its range (values
   !> without rounding or scatter, a simulation's: a hold sample 1e-12 short of its level
   !> had been no part of the hold)
   pure real(dp) function noise_scale(t, v) result(scale)
      real(dp), intent(in) :: t(:), v(:)
      scale = max(quantum(v), signal_noise(t, v), unrounded_floor*(maxval(v) - minval(v)))
   end function noise_scale

   !> Noise standard deviation of a signal v sampled at times t: the robust scatter (median
   !> absolute deviation) of each sample's residual from the line through its two
   !> neighbours at their times, over the residual's own noise factor (see
   !> fit_residual_sd). Where the sampling is regular this is noise_sd's second
   !> difference; at uneven times the neighbours' line, not their mean, is the reference
   !> (ramps logged at times jittered by 40 % of their step had read as noise of 8e-5 and
   !> been smoothed 2e-4 off the command). The smaller of that and the same read in sample
   !> order is the noise: values smooth in their order but not in their times are a
   !> regular sampling whose time stamps scatter, not noise of the values. Nor is a smooth
   !> signal's curvature noise: independent noise leaves the same scatter about the
   !> polynomial through more neighbours (degree 3 through two each side, up to degree 9
   !> through five), a well-sampled smooth signal a scatter that falls with each degree;
   !> while it falls to under half, the last was the signal's, and the noise is read where
   !> it stops falling (see falling_fit_sd). A sine logged 10 times a period had read as
   !> noise of 9.4e-4, its own curvature in its second differences; 12 times that exceeded
   !> its range, no turning point was found and its simulation failed. It reads 1.1e-7
   pure real(dp) function signal_noise(t, v) result(sd)
      real(dp), intent(in) :: t(:), v(:)
      real(dp) :: at_times
      integer :: i
      sd = max(falling_fit_sd([(real(i, dp), i=1, size(v))], v), 0.0_dp)
      ! (no reading at the times, where too many share one, leaves the order's)
      at_times = falling_fit_sd(t, v)
      if (at_times >= 0.0_dp) sd = min(sd, at_times)
   end function signal_noise

   !> The noise of v at positions t read from local fits of rising degree (see
   !> signal_noise); -1 without a reading (too few samples)
   pure real(dp) function falling_fit_sd(t, v) result(sd)
      real(dp), intent(in) :: t(:), v(:)
      real(dp) :: next
      integer :: half
      sd = fit_residual_sd(t, v, 1, 3)
      if (sd < 0.0_dp) return
      do half = 2, max_half
         next = fit_residual_sd(t, v, half, fit_residuals)
         ! (too few samples for the next degree, next < 0, is no reading and no fall)
         if (.not. (next >= 0.0_dp .and. next < 0.5_dp*sd)) exit
         sd = next
      end do
   end function falling_fit_sd

   !> The robust standard deviation (1.4826 times the median absolute residual) of the
   !> residuals of v(i) from the polynomial of degree 2 half - 1 through v(i - half:i + half)
   !> but v(i) at their times t, each over its noise factor (1 plus the sum of its squared
   !> interpolation weights, square-rooted, for independent noise); -1 for fewer than least
   !> residuals (a sample whose neighbours share a time has none)
   pure real(dp) function fit_residual_sd(t, v, half, least) result(sd)
      real(dp), intent(in) :: t(:), v(:)
      integer, intent(in) :: half, least
      real(dp) :: r(max(size(v) - 2*half, 0)), w, pred, ss
      integer :: i, j, l, m
      logical :: ok
      sd = -1.0_dp
      m = 0
      do i = half + 1, size(v) - half
         pred = 0.0_dp
         ss = 1.0_dp
         ok = .true.
         do j = i - half, i + half
            if (j == i) cycle
            w = 1.0_dp
            do l = i - half, i + half
               if (l == i .or. l == j) cycle
               if (.not. abs(t(j) - t(l)) > 0.0_dp) then
                  ok = .false.
                  exit
               end if
               w = w*(t(i) - t(l))/(t(j) - t(l))
            end do
            if (.not. ok) exit
            pred = pred + w*v(j)
            ss = ss + w**2
         end do
         if (.not. ok) cycle
         m = m + 1
         r(m) = abs(v(i) - pred)/sqrt(ss)
      end do
      if (m < least) return
      sd = 1.4826_dp*median(r(:m))
   end function fit_residual_sd

   !> Noise standard deviation of a sampled signal from its second differences, robustly
   !> (median absolute deviation): a smooth signal's second difference is far below the noise
   !> at the sampling rate, white noise gives var(d2) = 6 sd**2. lag: the differences taken
   !> that many samples apart (1 unless given); independent noise gives the same sd at every
   !> lag, noise correlated from sample to sample a larger one at a larger lag
   pure real(dp) function noise_sd(y, lag) result(sd)
      real(dp), intent(in) :: y(:)
      integer, intent(in), optional :: lag
      real(dp), allocatable :: d(:)
      integer :: n, k
      n = size(y)
      k = 1
      if (present(lag)) k = max(lag, 1)
      sd = 0.0_dp
      if (n < 2*k + 3) return
      d = abs(y(2*k + 1:n) - 2.0_dp*y(k + 1:n - k) + y(1:n - 2*k))
      sd = 1.4826_dp*median(d)/sqrt(6.0_dp)
   end function noise_sd

   !> How far the noise of y is from independent: noise_sd from second differences lag
   !> samples apart over that from neighbours (1 for independent noise, above for noise
   !> correlated from sample to sample); 0 where y has too few points
   pure real(dp) function noise_lag_ratio(y, lag) result(ratio)
      real(dp), intent(in) :: y(:)
      integer, intent(in) :: lag
      real(dp) :: sd1
      ratio = 0.0_dp
      sd1 = noise_sd(y)
      if (sd1 > 0.0_dp) ratio = noise_sd(y, lag)/sd1
   end function noise_lag_ratio

   !> The rounding of recorded values: the largest q = s/k (s the smallest non-zero step
   !> between neighbours, k = 1 to 4) of which nearly every value (95 %) is a whole multiple,
   !> with steps of typically 1.5 quanta or more, where the rounding shows (see
   !> jitter_share); 0 when there is none (a simulation's values, noise without rounding,
   !> or values that all fall on the grid of their own sampling). A logger's
   !> step can be several quanta (an Alloy 617 strain recorded to 1e-5 moves by 2e-5 at
   !> least), and samples of a repeated time, averaged, fall between the quanta.
   pure real(dp) function quantum(v) result(q)
      real(dp), intent(in) :: v(:)
      real(dp), allocatable :: steps(:)
      integer :: k, n
      q = signal_resolution(v)
      if (q == 0.0_dp) return
      n = size(v)
      steps = abs(v(2:) - v(:n - 1))
      steps = pack(steps, steps > 0.0_dp)
      do k = 1, 4
         if (count(abs(v/(q/k) - anint(v/(q/k))) <= 1.0e-3_dp) >= 0.95_dp*n) then
            q = q/k
            ! Steps of typically one quantum are a signal creeping by its resolution, whose
            ! own scatter is the finer measure of its noise; steps alike along every ramp
            ! are a regular sampling of steady ramps, whose values fall on a grid of their
            ! own (a 1e-3/s ramp sampled every 0.5 s from 0.4 s lies on 1e-4, which as a
            ! quantum made every branch a straight line 1.9e-4 off its samples)
            if (median(steps) < 1.5_dp*q .or. .not. rounding_shows(v, q)) q = 0.0_dp
            return
         end if
      end do
      q = 0.0_dp
   end function quantum

   !> Whether rounding to q shows in v as jitter: of the samples inside ramps (the two
   !> steps either side of it move the same way; a turn's neighbours are left out, where a
   !> reversal between samples shortens a step), at least jitter_share have a second
   !> difference of half a quantum or more. True where no sample lies inside a ramp (a slow
   !> ramp's rounding makes plateaus, which is rounding)
   pure logical function rounding_shows(v, q)
      real(dp), intent(in) :: v(:), q
      real(dp) :: st(4)
      integer :: k, inside, jitter
      inside = 0
      jitter = 0
      do k = 3, size(v) - 2
         st = v(k - 1:k + 2) - v(k - 2:k + 1)
         if (.not. (all(st > 0.0_dp) .or. all(st < 0.0_dp))) cycle
         inside = inside + 1
         if (abs(v(k + 1) - 2.0_dp*v(k) + v(k - 1)) >= 0.5_dp*q) jitter = jitter + 1
      end do
      rounding_shows = inside == 0 .or. jitter >= jitter_share*inside
   end function rounding_shows

   !> Resolution of recorded values: their smallest non-zero step between neighbours
   !> (0 when all are equal)
   pure real(dp) function signal_resolution(v) result(q)
      real(dp), intent(in) :: v(:)
      real(dp) :: d
      integer :: k
      q = huge(1.0_dp)
      do k = 2, size(v)
         d = abs(v(k) - v(k - 1))
         if (d > 0.0_dp) q = min(q, d)
      end do
      if (q == huge(1.0_dp)) q = 0.0_dp
   end function signal_resolution

   !> Discrete smoothing spline of one branch (the Whittaker smoother on uneven times),
   !> spatially adaptive: z minimises sum w (y - z)**2 + lambda sum_k h_k (z'')_k**2 with z''
   !> the second divided differences and h_k their time spans. lambda makes the branch's
   !> residual RMS sigma (the discrepancy principle; bisection in log10 lambda); then, where
   !> the residual over a window of samples exceeds twice that (the bias of a stiff curve at
   !> a rounded turn or a real feature), the weights rise until it does not. So the curve is
   !> stiff along the straight ramps, which the integrator then crosses in long steps, and
   !> follows the signal where it bends. The end samples are held (weight 1e8). Fewer than 4
   !> samples are returned as they are.
   pure function smooth_branch(t, y, sigma) result(z)
      real(dp), intent(in) :: t(:), y(:), sigma
      real(dp) :: z(size(y))
      real(dp) :: u(size(t)), w(size(y)), lo, hi, mid, scale, lambda
      logical :: biased(size(y))
      integer :: it, n
      n = size(y)
      z = y
      if (n < 4 .or. sigma <= 0.0_dp) return
      ! Times scaled to [0, 1]; lambda relative to the penalty's largest entry (about
      ! 1/hmin**3), from no smoothing (1e-12) to a straight line within rounding (1e10)
      u = (t - t(1))/(t(n) - t(1))
      scale = minval(u(2:n) - u(1:n - 1))**3
      ! The ends, the turning points, are kept: the measured extremes of the strain
      w = 1.0_dp
      w([1, n]) = 1.0e8_dp
      lo = -12.0_dp
      hi = 10.0_dp
      do it = 1, 40
         mid = 0.5_dp*(lo + hi)
         z = whittaker(u, y, w, scale*pow10_dp(mid))
         if (rms(z - y) > sigma) then
            hi = mid
         else
            lo = mid
         end if
      end do
      lambda = scale*pow10_dp(lo)
      do it = 1, 20
         z = whittaker(u, y, w, lambda)
         biased = local_excess(z - y, 2.0_dp*sigma)
         if (.not. any(biased)) exit
         where (biased) w = 4.0_dp*w
      end do
   end function smooth_branch

   pure real(dp) function rms(r)
      real(dp), intent(in) :: r(:)
      rms = sqrt(sum(r**2)/real(size(r), dp))
   end function rms

   !> The samples of the windows (of window samples, or all of r when shorter) in which the
   !> RMS of r exceeds bound
   pure function local_excess(r, bound) result(flag)
      real(dp), intent(in) :: r(:), bound
      logical :: flag(size(r))
      real(dp) :: c(0:size(r))
      integer :: k, m, n
      n = size(r)
      m = min(window, n)
      c(0) = 0.0_dp
      do k = 1, n
         c(k) = c(k - 1) + r(k)**2
      end do
      flag = .false.
      do k = m, n
         if (c(k) - c(k - m) > real(m, dp)*bound**2) flag(k - m + 1:k) = .true.
      end do
   end function local_excess

   !> Solve (W + lambda D^T H D) z = W y: a symmetric positive definite pentadiagonal system,
   !> by its banded Cholesky factorisation
   pure function whittaker(u, y, wt, lambda) result(z)
      real(dp), intent(in) :: u(:), y(:), wt(:), lambda
      real(dp) :: z(size(y))
      real(dp) :: a0(size(y)), a1(size(y)), a2(size(y)), d(0:2), h1, h2, hm, w
      real(dp) :: c0(size(y)), c1(size(y)), c2(size(y))
      integer :: k, n, p, q
      n = size(y)
      ! Bands of the matrix: a0(i) = A(i,i), a1(i) = A(i,i-1), a2(i) = A(i,i-2)
      a0 = wt
      a1 = 0.0_dp
      a2 = 0.0_dp
      do k = 1, n - 2
         h1 = u(k + 1) - u(k)
         h2 = u(k + 2) - u(k + 1)
         hm = 0.5_dp*(h1 + h2)
         d = [1.0_dp/h1, -(1.0_dp/h1 + 1.0_dp/h2), 1.0_dp/h2]/hm
         w = lambda*hm
         do p = 0, 2
            a0(k + p) = a0(k + p) + w*d(p)**2
            do q = 0, p - 1
               if (p - q == 1) then
                  a1(k + p) = a1(k + p) + w*d(p)*d(q)
               else
                  a2(k + p) = a2(k + p) + w*d(p)*d(q)
               end if
            end do
         end do
      end do
      ! Cholesky: c0 the diagonal of L, c1 and c2 its first and second subdiagonals
      do k = 1, n
         c2(k) = 0.0_dp
         c1(k) = 0.0_dp
         if (k > 2) c2(k) = a2(k)/c0(k - 2)
         if (k > 1) then
            c1(k) = a1(k)
            if (k > 2) c1(k) = c1(k) - c2(k)*c1(k - 1)
            c1(k) = c1(k)/c0(k - 1)
         end if
         c0(k) = sqrt(a0(k) - c1(k)**2 - c2(k)**2)
      end do
      z = wt*y
      do k = 1, n
         if (k > 1) z(k) = z(k) - c1(k)*z(k - 1)
         if (k > 2) z(k) = z(k) - c2(k)*z(k - 2)
         z(k) = z(k)/c0(k)
      end do
      do k = n, 1, -1
         if (k < n) z(k) = z(k) - c1(k + 1)*z(k + 1)
         if (k < n - 1) z(k) = z(k) - c2(k + 2)*z(k + 2)
         z(k) = z(k)/c0(k)
      end do
   end function whittaker

   !> Second derivatives at the knots of the natural cubic spline through (t, z)
   pure function natural_spline(t, z) result(m)
      real(dp), intent(in) :: t(:), z(:)
      real(dp) :: m(size(z))
      real(dp) :: diag(size(z)), rhs(size(z)), h(size(z)), w
      integer :: k, n
      n = size(z)
      m = 0.0_dp
      if (n < 3) return
      h(1:n - 1) = t(2:n) - t(1:n - 1)
      ! Tridiagonal system for m(2:n-1), m(1) = m(n) = 0; Thomas algorithm
      do k = 2, n - 1
         diag(k) = 2.0_dp*(h(k - 1) + h(k))
         rhs(k) = 6.0_dp*((z(k + 1) - z(k))/h(k) - (z(k) - z(k - 1))/h(k - 1))
      end do
      do k = 3, n - 1
         w = h(k - 1)/diag(k - 1)
         diag(k) = diag(k) - w*h(k - 1)
         rhs(k) = rhs(k) - w*rhs(k - 1)
      end do
      m(n - 1) = rhs(n - 1)/diag(n - 1)
      do k = n - 2, 2, -1
         m(k) = (rhs(k) - h(k)*m(k + 1))/diag(k)
      end do
   end function natural_spline
end module usharp_forcing
