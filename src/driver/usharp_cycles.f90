!> The cyclic structure of a measured history: selected cycles of a fatigue test (recorded
!> pieces with unrecorded cycles between them) joined by the cycling that took place in the
!> gaps, and the turning points (strain peaks) of a history, where each cycle's peak stress
!> is compared.
module usharp_cycles
   use usharp_kinds, only: dp
   use usharp_error, only: error_type, fatal_error
   use usharp_strings, only: real_str
   use usharp_history, only: history_type, history_from_points, segment_of
   use usharp_forcing, only: measured_history, turning_points
   use usharp_sort, only: median
   implicit none
   private

   public :: record_starts, gap_filled_history, fill_gap, peak_corners, match_peaks

   !> A time step longer than this many times the median step of the samples is a gap
   !> (unrecorded cycles); within a recorded cycle the steps vary by a factor of 10 at most
   real(dp), parameter, public :: gap_factor = 50.0_dp
   !> Turning points of a recorded piece: confirmed after a return of this fraction of its range
   real(dp), parameter :: turn_fraction = 0.1_dp

   !> The cycling of a recorded piece at one of its ends: the upper and lower turning values,
   !> the value and direction (+1 rising, -1 falling) at the end, and the time of a half
   !> cycle (s, 0 when the piece does not reverse)
   type, public :: cycle_shape
      real(dp) :: upper = 0.0_dp, lower = 0.0_dp, value = 0.0_dp, half = 0.0_dp
      integer :: dir = 0
   end type cycle_shape

contains

   !> First index of each recorded piece of times t: 1, and every k with t(k) - t(k-1)
   !> longer than record_limit(t, gap_time)
   pure function record_starts(t, gap_time) result(starts)
      real(dp), intent(in) :: t(:)
      !> s; 0: gap_factor times the median step
      real(dp), intent(in) :: gap_time
      integer, allocatable :: starts(:)
      real(dp) :: limit
      integer :: k
      starts = [1]
      if (size(t) < 3) return
      limit = record_limit(t, gap_time)
      do k = 2, size(t)
         if (t(k) - t(k - 1) > limit) starts = [starts, k]
      end do
   end function record_starts

   !> The longest time step of samples at times t that is no gap: gap_time (s) when it is
   !> positive, else gap_factor times their median step
   pure real(dp) function record_limit(t, gap_time) result(limit)
      real(dp), intent(in) :: t(:), gap_time
      limit = gap_time
      if (limit <= 0.0_dp .and. size(t) >= 2) limit = gap_factor*median(t(2:) - t(:size(t) - 1))
   end function record_limit

   !> A history from measured samples (t in s, v strain) whose recorded pieces (see
   !> record_starts) are each the smooth forcing of measured_history and whose gaps are filled
   !> with triangular cycles (fill_gap): upper and lower turning values and the time of a half
   !> cycle interpolated from the piece before the gap to the piece after it. range > 0
   !> (strain) states the cycles' range instead, about mean (strain); rate > 0 (per s) their
   !> rate. A piece that does not reverse (monotonic loading) is joined to the next by a
   !> straight line. spans(:, j): first and last time of recorded piece j (s). noise: as for
   !> measured_history (0: no smoothing). straight: every gap a straight line from the end of
   !> one piece to the start of the next (gap_fill = 'linear'), each piece smoothed on its own
   pure subroutine gap_filled_history(t, v, control, range, mean, rate, hist, spans, error, noise, &
                                      straight, gap_time)
      real(dp), intent(in) :: t(:), v(:)
      integer, intent(in) :: control
      real(dp), intent(in) :: range, mean, rate
      type(history_type), intent(out) :: hist
      real(dp), allocatable, intent(out) :: spans(:, :)
      type(error_type), allocatable, intent(out) :: error
      real(dp), intent(in), optional :: noise
      logical, intent(in), optional :: straight
      !> a time step longer than this is a gap (s; absent or 0: see record_starts)
      real(dp), intent(in), optional :: gap_time
      integer, allocatable :: starts(:), stops(:), kstops(:)
      character(len=:), allocatable :: where_text
      real(dp) :: limit
      type(history_type) :: piece
      type(cycle_shape) :: a, b
      real(dp), allocatable :: tt(:), vv(:), tk(:), vk(:), d2(:), tc(:), vc(:)
      integer :: i, j, p0, p1, np
      limit = 0.0_dp
      if (present(gap_time)) limit = gap_time
      starts = [record_starts(t, limit), size(t) + 1]
      np = size(starts) - 1
      ! A recorded piece holds a cycle or a stretch of one: a sample or two between two gaps
      ! are no piece, but most likely a stretch logged more slowly than the rest (a hold)
      do j = 1, np
         if (starts(j + 1) - starts(j) >= 3 .or. np == 1) cycle
         where_text = 'the sample at t = '//real_str(t(starts(j)), 'f0.2')//' s lies'
         if (starts(j + 1) - starts(j) > 1) where_text = 'the samples at t = '// &
            real_str(t(starts(j)), 'f0.2')//' and '//real_str(t(starts(j) + 1), 'f0.2')//' s lie'
         call fatal_error(error, where_text//' alone between two gaps (time steps longer than '// &
            real_str(record_limit(t, limit), 'g0.4')//' s, taken as unrecorded cycles): a hold '// &
            'logged more slowly than the ramps? Give gap_time (s) longer than its steps')
         return
      end do
      allocate (spans(2, np))
      if (np == 1) then
         call measured_history(t, v, control, hist, error, noise)
         spans(:, 1) = [t(1), t(size(t))]
         return
      end if
      allocate (tt(0), vv(0), tk(0), vk(0), d2(0), stops(0), kstops(0))
      do j = 1, np
         p0 = starts(j)
         p1 = starts(j + 1) - 1
         spans(:, j) = [t(p0), t(p1)]
         call measured_history(t(p0:p1), v(p0:p1), control, piece, error, noise)
         if (allocated(error)) return
         if (j > 1) then
            ! The filled cycles' corners are knots and stops both (d2 = 0: straight between)
            b = piece_end(piece, .false.)
            ! A stated rate at which not even a half cycle fits in the gap would be squeezed
            ! into it at another rate (1e-5/s meant as 1e-3/s)
            if (rate > 0.0_dp .and. .not. straight_fill()) then
               if (half_cycle(a) > piece%t(1) - tt(size(tt))) then
                  call fatal_error(error, 'strain_rate = '//real_str(rate, 'es9.2')//' /s: a half cycle '// &
                     'of the cycles that fill the gaps takes '//real_str(half_cycle(a), 'es9.2')//' s, '// &
                     'longer than the gap from t = '//real_str(tt(size(tt)), 'f0.2')//' to '// &
                     real_str(piece%t(1), 'f0.2')//' s (is strain_rate per s?)')
                  return
               end if
            end if
            call fill_gap(tt(size(tt)), a, piece%t(1), b, range, mean, rate, tc, vc)
            if (present(straight)) then
               if (straight) then
                  tc = tc(:0)
                  vc = vc(:0)
               end if
            end if
            stops = [stops, size(tt) + [(i, i=1, size(tc))]]
            kstops = [kstops, size(tk) + [(i, i=1, size(tc))]]
            tt = [tt, tc]
            vv = [vv, vc]
            tk = [tk, tc]
            vk = [vk, vc]
            d2 = [d2, spread(0.0_dp, 1, size(tc))]
         end if
         stops = [stops, size(tt) + piece%corners()]
         if (piece%smooth()) then
            kstops = [kstops, size(tk) + piece%kstops]
            tk = [tk, piece%tk]
            vk = [vk, piece%vk]
            d2 = [d2, piece%d2]
         else
            kstops = [kstops, size(tk) + [(i, i=1, size(piece%t))]]
            tk = [tk, piece%t]
            vk = [vk, piece%v]
            d2 = [d2, spread(0.0_dp, 1, size(piece%t))]
         end if
         tt = [tt, piece%t]
         vv = [vv, piece%v]
         a = piece_end(piece, .true.)
      end do
      call history_from_points(tt, vv, control, hist, error)
      if (allocated(error)) return
      ! Without a smoothed piece it is piecewise linear through every point
      if (size(stops) == size(tt) .and. all(d2 == 0.0_dp)) return
      hist%tk = tk
      hist%vk = vk
      hist%d2 = d2
      hist%stops = stops
      hist%kstops = kstops
   contains
      pure logical function straight_fill()
         straight_fill = .false.
         if (present(straight)) straight_fill = straight
      end function straight_fill
      !> The half cycle (s) of the fill at the stated rate: its range (stated, else the
      !> recorded piece's) over the rate
      pure real(dp) function half_cycle(c)
         type(cycle_shape), intent(in) :: c
         if (range > 0.0_dp) then
            half_cycle = range/rate
         else
            half_cycle = (c%upper - c%lower)/rate
         end if
      end function half_cycle
   end subroutine gap_filled_history

   !> The cycling of a recorded piece at its end (last = true) or its start: the turning
   !> values of its last (first) full cycle, or its extremes when it has none; the time of a
   !> half cycle; dir 0 at the start of a piece without a turning point
   pure function piece_end(piece, last) result(s)
      type(history_type), intent(in) :: piece
      logical, intent(in) :: last
      type(cycle_shape) :: s
      integer, allocatable :: tp(:)
      real(dp) :: vr(size(piece%v))
      integer :: n, m, j
      vr = piece%v
      n = size(vr)
      s%upper = maxval(vr)
      s%lower = minval(vr)
      tp = turning_points(vr, turn_fraction*(s%upper - s%lower))
      m = size(tp)
      ! The machine's timing, robust to a glitch of the extensometer that would bias a rate
      ! or a spacing of turning points: a piece holds whole cycles (its travel between its
      ! turning points in ranges, rounded), each a sample interval longer than its samples span
      if (m >= 3) s%half = (piece%t(n) - piece%t(1) + median(piece%t(2:) - piece%t(:n - 1)))/ &
         real(2*max(1, nint(sum(abs(vr(tp(2:)) - vr(tp(:m - 1))))/(2.0_dp*(s%upper - s%lower)))), dp)
      if (last) then
         s%value = vr(n)
         s%dir = nint(sign(1.0_dp, vr(n) - vr(tp(m - 1))))
         if (vr(n) == vr(tp(m - 1))) s%dir = 0
         ! The last inner maximum and minimum
         if (m >= 4) then
            j = m - 1
            s%upper = max(vr(tp(j)), vr(tp(j - 1)))
            s%lower = min(vr(tp(j)), vr(tp(j - 1)))
         end if
      else
         s%value = vr(1)
         s%dir = nint(sign(1.0_dp, vr(tp(2)) - vr(1)))
         if (vr(tp(2)) == vr(1)) s%dir = 0
         if (m >= 4) then
            s%upper = max(vr(tp(2)), vr(tp(3)))
            s%lower = min(vr(tp(2)), vr(tp(3)))
         end if
      end if
   end function piece_end

   !> The corners (tc, vc) strictly inside a gap from time ta (the end a of a recorded piece)
   !> to tb (the start b of the next): k reversals, k of the parity that leaves a in its
   !> direction and arrives at b in its. Turning values and the time of a half cycle go
   !> linearly from a's to b's (range > 0: mean +- range/2; rate > 0: a half cycle of
   !> range/rate); each leg takes its share of a half cycle, and k is the number whose legs'
   !> time is nearest the gap's (the cycles the test ran through), their times then scaled to
   !> fill it. A gap after a piece that does not reverse, or into one that does not move, is a
   !> straight line (no corners).
   pure subroutine fill_gap(ta, a, tb, b, range, mean, rate, tc, vc)
      real(dp), intent(in) :: ta, tb, range, mean, rate
      type(cycle_shape), intent(in) :: a, b
      real(dp), allocatable, intent(out) :: tc(:), vc(:)
      real(dp) :: ua, la, ub, lb, ha, hb, h
      real(dp), allocatable :: p(:), c(:)
      integer :: k, kmin, kbest, kk, da, db
      da = a%dir
      db = b%dir
      allocate (tc(0), vc(0))
      ua = a%upper; la = a%lower; ub = b%upper; lb = b%lower
      ha = a%half; hb = b%half
      if (hb <= 0.0_dp) hb = ha
      if (range > 0.0_dp) then
         ua = mean + 0.5_dp*range; ub = ua
         la = mean - 0.5_dp*range; lb = la
      end if
      if (rate > 0.0_dp) then
         ha = (ua - la)/rate
         hb = (ub - lb)/rate
      end if
      if (ha <= 0.0_dp .or. da == 0 .or. db == 0 .or. ua <= la .or. ub <= lb) return
      if (da == db) then
         kmin = 2
         if (da*(b%value - a%value) > 0.0_dp) kmin = 0
      else
         kmin = 1
      end if
      ! Each further pair of reversals takes about a cycle: estimate, then look around it
      h = 0.5_dp*(ha + hb)
      kk = kmin + 2*max(0, nint((tb - ta - duration(kmin))/(2.0_dp*h)))
      kbest = kmin
      do k = max(kmin, kk - 4), kk + 4, 2
         if (abs(duration(k) - (tb - ta)) < abs(duration(kbest) - (tb - ta))) kbest = k
      end do
      if (kbest == 0) return
      p = peaks(kbest)
      c = leg_times(kbest)
      tc = ta + (tb - ta)*c(:kbest)/c(kbest + 1)
      ! A reversal at the very value the fill leaves from or arrives at is no corner
      vc = pack(p, tc > ta .and. tc < tb)
      tc = pack(tc, tc > ta .and. tc < tb)
   contains
      !> The turning values of a fill with k reversals
      pure function peaks(k) result(pk)
         integer, intent(in) :: k
         real(dp) :: pk(k)
         real(dp) :: f
         integer :: j, d
         d = da
         do j = 1, k
            f = real(j, dp)/real(k + 1, dp)
            if (d > 0) then
               pk(j) = (1.0_dp - f)*ua + f*ub
            else
               pk(j) = (1.0_dp - f)*la + f*lb
            end if
            d = -d
         end do
         ! Never turn short of the values the fill leaves from and arrives at
         if (k > 0) then
            pk(1) = merge(max(pk(1), a%value), min(pk(1), a%value), da > 0)
            pk(k) = merge(max(pk(k), b%value), min(pk(k), b%value), db < 0)
         end if
      end function peaks
      !> Times at the end of each of the k + 1 legs of a fill with k reversals, from the start
      !> of the gap: a leg takes the half cycle's time times its share of the range there
      pure function leg_times(k) result(c)
         integer, intent(in) :: k
         real(dp) :: c(k + 1)
         real(dp) :: v(0:k + 1), f
         integer :: j
         v(0) = a%value
         v(1:k) = peaks(k)
         v(k + 1) = b%value
         do j = 1, k + 1
            f = (real(j, dp) - 0.5_dp)/real(k + 1, dp)
            c(j) = ((1.0_dp - f)*ha + f*hb)*abs(v(j) - v(j - 1))/((1.0_dp - f)*(ua - la) + f*(ub - lb))
            if (j > 1) c(j) = c(j) + c(j - 1)
         end do
      end function leg_times
      pure real(dp) function duration(k)
         integer, intent(in) :: k
         real(dp) :: c(k + 1)
         c = leg_times(k)
         duration = c(k + 1)
      end function duration
   end subroutine fill_gap

   !> Indices of the corners of hist that are its turning points: kind +1 a maximum, -1 a
   !> minimum (its first and last points are neither); a hold at a peak counts at its start
   pure subroutine peak_corners(hist, idx, kind)
      type(history_type), intent(in) :: hist
      integer, allocatable, intent(out) :: idx(:), kind(:)
      integer, allocatable :: c(:)
      integer :: i, j, k
      real(dp) :: prev, here, next
      c = hist%corners()
      allocate (idx(size(c)), kind(size(c)))
      j = 0
      do i = 2, size(c) - 1
         prev = hist%v(c(i - 1))
         here = hist%v(c(i))
         ! A hold counts at its start; what follows it decides: a pause inside a ramp (a
         ! hold logged at its two ends, two corners of one value) is no peak
         if (here == prev) cycle
         k = i + 1
         do while (k < size(c))
            if (hist%v(c(k)) /= here) exit
            k = k + 1
         end do
         next = hist%v(c(k))
         if (here > prev .and. here >= next) then
            j = j + 1
            idx(j) = c(i)
            kind(j) = 1
         else if (here < prev .and. here <= next) then
            j = j + 1
            idx(j) = c(i)
            kind(j) = -1
         end if
      end do
      idx = idx(:j)
      kind = kind(:j)
   end subroutine peak_corners

   !> The turning point of hist at which each measured peak (time tp, s, ascending for each
   !> kind; kind kp: +1 a maximum, -1 a minimum) is compared: the turning point of its kind
   !> nearest the peak's time, shifted by the drift of the match before (the simulated time
   !> of the last matched turning point less its peak's), if it lies within a quarter of the
   !> local spacing of those turning points and no earlier peak took it; else the one nearest
   !> the peak's own time, so bounded (a measured peak may come before the strain's, as a
   !> first-cycle overshoot does). The drift follows the cycles through which a gap between
   !> recorded cycles is filled: their period, interpolated, differs from the test's by a
   !> little, which over hundreds of cycles grew to more than a quarter cycle and had left
   !> most of their peaks unmatched. corner(i) its index in hist (0: none, e.g. a peak after
   !> the history's end) and cyc(i) the number of the simulated cycle (1 for the first
   !> turning point of its kind)
   pure subroutine match_peaks(hist, tp, kp, corner, cyc)
      type(history_type), intent(in) :: hist
      real(dp), intent(in) :: tp(:)
      integer, intent(in) :: kp(:)
      integer, allocatable, intent(out) :: corner(:), cyc(:)
      integer, allocatable :: idx(:), kind(:), sel(:)
      logical, allocatable :: taken(:)
      real(dp), allocatable :: tk(:)
      real(dp) :: drift
      integer :: i, s, j
      logical :: tracking
      call peak_corners(hist, idx, kind)
      allocate (corner(size(tp)), cyc(size(tp)))
      corner = 0
      cyc = 0
      do s = -1, 1, 2
         sel = pack(idx, kind == s)
         if (size(sel) == 0) cycle
         tk = hist%t(sel)
         allocate (taken(size(sel)))
         taken = .false.
         drift = 0.0_dp
         tracking = .false.
         do i = 1, size(tp)
            if (kp(i) /= s) cycle
            j = 0
            if (tracking) j = nearest_within(tp(i) + drift)
            if (j == 0) j = nearest_within(tp(i))
            if (j == 0) then
               tracking = .false.
               cycle
            end if
            taken(j) = .true.
            corner(i) = sel(j)
            cyc(i) = j
            drift = tk(j) - tp(i)
            tracking = .true.
         end do
         deallocate (taken)
      end do

   contains

      !> The untaken turning point of tk nearest t within a quarter of its local spacing
      !> (0: none)
      pure integer function nearest_within(t) result(jn)
         real(dp), intent(in) :: t
         real(dp) :: spacing
         integer :: lo, hi
         lo = segment_of(tk, t)
         hi = min(lo + 1, size(tk))
         jn = merge(lo, hi, abs(tk(lo) - t) <= abs(tk(hi) - t))
         if (size(tk) > 1) then
            spacing = tk(min(jn + 1, size(tk))) - tk(max(jn - 1, 1))
            if (jn > 1 .and. jn < size(tk)) spacing = 0.5_dp*spacing
         else
            spacing = hist%end_time() - hist%t(1)
         end if
         if (abs(tk(jn) - t) > 0.25_dp*spacing .or. taken(jn)) jn = 0
      end function nearest_within
   end subroutine match_peaks
end module usharp_cycles
