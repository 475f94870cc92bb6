!> Load histories: piecewise-linear control of strain (-) or stress (model unit) in time (s),
!> and the generators of the standard tests.
module usharp_history
   use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
   use usharp_kinds, only: dp
   use usharp_math, only: pow_dp, cubic_piece
   use usharp_error, only: error_type, fatal_error
   use usharp_strings, only: str, real_str
   implicit none
   private

   public :: history_type, control_strain, control_stress, segment_type
   public :: history_from_points, thesis_lcf_history, relaxation_history, ratchet_history
   public :: cyclic_history, tensile_history, creep_history, output_times, thesis_history, segment_of
   public :: rate_jump_history, spline_eval, knot_piece, add_tmf_temperature

   !> Control modes
   integer, parameter :: control_strain = 1, control_stress = 2
   !> The most corners a history, or output times a test, may have: a simulation keeps six
   !> arrays of its outputs, 480 MB at this size (far beyond hundreds of thousands of points
   !> of a whole test programme), and counts beyond it overflow before memory runs out
   integer, parameter, public :: max_points = 10000000

   !> Piecewise-linear history: value v(k) at time t(k); t strictly increasing. A smooth
   !> history (a measured signal as forcing, usharp_forcing) is instead a cubic spline
   !> through knots (tk, vk), a few of the samples, with second derivatives d2, twice
   !> continuously differentiable between its stops (the turning points, where it has a
   !> corner and d2 = 0); its samples (t, v) lie on the spline
   type :: history_type
      integer :: control = control_strain
      real(dp), allocatable :: t(:)  !< corner times (samples of a smooth history), s
      real(dp), allocatable :: v(:)  !< strain (-) or stress (model unit) at the corners
      !> smooth only: the spline's knots (s; strain, or stress in the model unit), the
      !> second derivative there (per s**2), and the indices of the corners (the first and
      !> last included) among the samples (stops) and among the knots (kstops)
      real(dp), allocatable :: tk(:), vk(:), d2(:)
      integer, allocatable :: stops(:), kstops(:)
      !> Non-isothermal only: the temperature at the corners (K), linear between them
      real(dp), allocatable :: temp(:)
   contains
      procedure :: value_at => history_value_at
      procedure :: end_time => history_end_time
      procedure :: segment => history_segment
      procedure :: smooth => history_smooth
      procedure :: corners => history_corners
      procedure :: forcing => history_forcing
      procedure :: add_ramp => history_add_ramp
      procedure :: scale => history_scale
   end type history_type

   !> One linear piece of a history: control, start time (s), start value and slope (per s)
   !> of the strain (-) or stress (model unit)
   type :: segment_type
      integer :: control = control_strain
      real(dp) :: t0 = 0.0_dp, v0 = 0.0_dp, slope = 0.0_dp
   contains
      procedure :: value => segment_value
   end type segment_type

contains

   !> Build a history from corner points, checking them
   pure subroutine history_from_points(t, v, control, hist, error)
      real(dp), intent(in) :: t(:), v(:)
      integer, intent(in) :: control
      type(history_type), intent(out) :: hist
      type(error_type), allocatable, intent(out) :: error
      integer :: k
      if (size(t) /= size(v)) then
         call fatal_error(error, 'history has '//str(size(t))//' times but '//str(size(v))//' values')
         return
      end if
      if (size(t) < 2) then
         call fatal_error(error, 'history needs at least 2 points, got '//str(size(t)))
         return
      end if
      do k = 1, size(t)
         if (.not. (ieee_is_finite(t(k)) .and. ieee_is_finite(v(k)))) then
            call fatal_error(error, 'history point '//str(k)//' is not finite')
            return
         end if
         if (k > 1) then
            if (t(k) <= t(k - 1)) then
               call fatal_error(error, 'history time is not increasing at point '//str(k)// &
                  ' (t = '//str(t(k))//' s after '//str(t(k - 1))//' s)')
               return
            end if
         end if
      end do
      hist%control = control
      hist%t = t
      hist%v = v
   end subroutine history_from_points

   !> Value of the history at time t (linear inside, constant beyond the ends)
   pure real(dp) function history_value_at(self, t) result(val)
      class(history_type), intent(in) :: self
      real(dp), intent(in) :: t
      integer :: k
      real(dp) :: rate
      if (t <= self%t(1)) then
         val = self%v(1)
      else if (t >= self%t(size(self%t))) then
         val = self%v(size(self%v))
      else if (self%smooth()) then
         call spline_eval(self%tk, self%vk, self%d2, 1, size(self%tk), t, val, rate)
      else
         k = segment_of(self%t, t)
         val = self%v(k) + (self%v(k + 1) - self%v(k))*(t - self%t(k))/(self%t(k + 1) - self%t(k))
      end if
   end function history_value_at

   !> Whether the history is a smooth (spline) forcing
   pure logical function history_smooth(self)
      class(history_type), intent(in) :: self
      history_smooth = allocated(self%d2)
   end function history_smooth

   !> Indices of the corners where an integrator must stop: every point of a piecewise-linear
   !> history, the stops of a smooth one
   pure function history_corners(self) result(idx)
      class(history_type), intent(in) :: self
      integer, allocatable :: idx(:)
      integer :: k
      if (self%smooth()) then
         idx = self%stops
      else
         idx = [(k, k=1, size(self%t))]
      end if
   end function history_corners

   !> A smooth history's spline as a history of its own, whose samples are the knots: what
   !> an integrator that steps across the knots follows
   pure function history_forcing(self) result(f)
      class(history_type), intent(in) :: self
      type(history_type) :: f
      f%control = self%control
      f%t = self%tk
      f%v = self%vk
      f%tk = self%tk
      f%vk = self%vk
      f%d2 = self%d2
      f%stops = self%kstops
      f%kstops = self%kstops
   end function history_forcing

   !> Add rate*(t - t(1)) to the history (rate per s): its samples and, of a smooth history,
   !> its knots, whose second derivatives a straight line leaves as they are
   pure subroutine history_add_ramp(self, rate)
      class(history_type), intent(inout) :: self
      real(dp), intent(in) :: rate
      real(dp) :: t0
      t0 = self%t(1)
      self%v = self%v + rate*(self%t - t0)
      if (self%smooth()) self%vk = self%vk + rate*(self%tk - t0)
   end subroutine history_add_ramp

   !> Multiply the history's values by factor (-): a control read through a channel of that
   !> gain. Linear, so the corners stay the corners and a spline stays the spline through
   !> its scaled knots
   pure subroutine history_scale(self, factor)
      class(history_type), intent(inout) :: self
      real(dp), intent(in) :: factor
      self%v = factor*self%v
      if (self%smooth()) then
         self%vk = factor*self%vk
         self%d2 = factor*self%d2
      end if
   end subroutine history_scale

   !> The cubic spline through (tk, vk) with second derivatives mk at time t, its interval
   !> found by bisection between k0 and k1
   pure subroutine spline_eval(tk, vk, mk, k0, k1, t, val, rate)
      real(dp), intent(in) :: tk(:), vk(:), mk(:), t
      integer, intent(in) :: k0, k1
      real(dp), intent(out) :: val, rate
      call cubic_piece(tk, vk, mk, knot_piece(tk, k0, k1, t), t, val, rate)
   end subroutine spline_eval

   !> The piece of a spline with knots tk that holds time t: the k with tk(k) <= t < tk(k + 1),
   !> by bisection between k0 and k1 (k0 when t < tk(k0), k1 - 1 when t >= tk(k1))
   pure integer function knot_piece(tk, k0, k1, t) result(lo)
      real(dp), intent(in) :: tk(:), t
      integer, intent(in) :: k0, k1
      integer :: hi, mid
      lo = k0
      hi = k1
      do while (hi - lo > 1)
         mid = (lo + hi)/2
         if (tk(mid) <= t) then
            lo = mid
         else
            hi = mid
         end if
      end do
   end function knot_piece

   !> Segment k of the history, from corner k to corner k+1
   pure type(segment_type) function history_segment(self, k) result(seg)
      class(history_type), intent(in) :: self
      integer, intent(in) :: k
      seg%control = self%control
      seg%t0 = self%t(k)
      seg%v0 = self%v(k)
      seg%slope = (self%v(k + 1) - self%v(k))/(self%t(k + 1) - self%t(k))
   end function history_segment

   !> A thermomechanical history: the temperature follows the command linearly between its
   !> extremes, tlow at the lowest command and thigh at the highest (in phase), or the other
   !> way round (out of phase); a piecewise-linear history only, whose corners then carry
   !> the temperature's corners too
   pure subroutine add_tmf_temperature(hist, tlow, thigh, in_phase, error)
      type(history_type), intent(inout) :: hist
      !> K
      real(dp), intent(in) :: tlow, thigh
      logical, intent(in) :: in_phase
      type(error_type), allocatable, intent(out) :: error
      real(dp) :: lo, hi
      real(dp), allocatable :: u(:)
      if (hist%smooth()) then
         call fatal_error(error, 'a temperature cycle needs a piecewise-linear history, '// &
                          'not a measured signal as smooth forcing')
         return
      end if
      lo = minval(hist%v)
      hi = maxval(hist%v)
      if (.not. hi > lo) then
         call fatal_error(error, 'a temperature cycle needs a command that changes')
         return
      end if
      u = (hist%v - lo)/(hi - lo)
      if (.not. in_phase) u = 1.0_dp - u
      hist%temp = tlow + (thigh - tlow)*u
   end subroutine add_tmf_temperature

   !> Value of a segment at time t (s), extended linearly
   elemental real(dp) function segment_value(self, t) result(v)
      class(segment_type), intent(in) :: self
      real(dp), intent(in) :: t
      v = self%v0 + self%slope*(t - self%t0)
   end function segment_value

   !> End time of the history, s
   pure real(dp) function history_end_time(self) result(t)
      class(history_type), intent(in) :: self
      t = self%t(size(self%t))
   end function history_end_time

   !> Index k with t(k) <= x < t(k+1) by bisection (t strictly increasing, t(1) <= x < t(n))
   pure integer function segment_of(t, x) result(k)
      real(dp), intent(in) :: t(:), x
      integer :: lo, hi, mid
      lo = 1
      hi = size(t)
      do while (hi - lo > 1)
         mid = (lo + hi)/2
         if (t(mid) <= x) then
            lo = mid
         else
            hi = mid
         end if
      end do
      k = lo
   end function segment_of

   !> The thesis's ramping-amplitude LCF test: peaks +a0, -a1, +a2, ... with a_k = a_first*m**k,
   !> m = (a_last/a_first)**(1/(npeaks-1)); each quarter cycle (zero to peak, peak to zero) takes
   !> quarter_time seconds. Thesis: a_first 0.0005, a_last 0.005, 12 peaks, 10 s (240 s).
   pure subroutine thesis_lcf_history(a_first, a_last, npeaks, quarter_time, hist, error)
      real(dp), intent(in) :: a_first, a_last, quarter_time
      integer, intent(in) :: npeaks
      type(history_type), intent(out) :: hist
      type(error_type), allocatable, intent(out) :: error
      real(dp), allocatable :: t(:), v(:)
      real(dp) :: m
      integer :: k
      if (npeaks < 2 .or. .not. (a_first > 0.0_dp .and. a_last > 0.0_dp .and. quarter_time > 0.0_dp)) then
         call fatal_error(error, 'thesis_lcf needs npeaks >= 2 and positive amplitudes and quarter_time')
         return
      end if
      if (npeaks > max_points/2) then
         call fatal_error(error, 'thesis_lcf: npeaks = '//str(npeaks)//' is more than the '// &
                          str(max_points/2)//' a history may have')
         return
      end if
      m = pow_dp(a_last/a_first, 1.0_dp/real(npeaks - 1, dp))
      allocate (t(2*npeaks + 1), v(2*npeaks + 1))
      t(1) = 0.0_dp
      v(1) = 0.0_dp
      do k = 0, npeaks - 1
         t(2*k + 2) = (2*k + 1)*quarter_time
         v(2*k + 2) = a_first*m**k*merge(1.0_dp, -1.0_dp, mod(k, 2) == 0)
         t(2*k + 3) = (2*k + 2)*quarter_time
         v(2*k + 3) = 0.0_dp
      end do
      call history_from_points(t, v, control_strain, hist, error)
   end subroutine thesis_lcf_history

   !> Multi-level relaxation: ramp to levels(i) in ramp_time, hold for holds(i) seconds.
   !> Thesis: levels 0.00075, 0.001; ramps 1 s; holds 600 s.
   pure subroutine relaxation_history(levels, ramp_time, holds, hist, error)
      real(dp), intent(in) :: levels(:), ramp_time, holds(:)
      type(history_type), intent(out) :: hist
      type(error_type), allocatable, intent(out) :: error
      real(dp), allocatable :: t(:), v(:)
      integer :: i
      if (size(levels) < 1 .or. size(holds) /= size(levels)) then
         call fatal_error(error, 'relaxation needs as many holds as levels (at least one): levels has '// &
                          str(size(levels))//', holds '//str(size(holds))//' (decimal commas? 600,5 reads as two values)')
         return
      end if
      if (ramp_time <= 0.0_dp .or. any(holds <= 0.0_dp)) then
         call fatal_error(error, 'relaxation ramp_time and holds must be > 0')
         return
      end if
      allocate (t(2*size(levels) + 1), v(2*size(levels) + 1))
      t(1) = 0.0_dp
      v(1) = 0.0_dp
      do i = 1, size(levels)
         t(2*i) = t(2*i - 1) + ramp_time
         v(2*i) = levels(i)
         t(2*i + 1) = t(2*i) + holds(i)
         v(2*i + 1) = levels(i)
      end do
      call history_from_points(t, v, control_strain, hist, error)
   end subroutine relaxation_history

   !> Strain ratcheting: from zero, +up then -down, repeated; seg_time seconds between peaks.
   !> Thesis: up 0.0005, down 0.00025, 15 repeats, 40 s (peak 0.4 %, 1200 s).
   pure subroutine ratchet_history(up, down, repeats, seg_time, hist, error)
      real(dp), intent(in) :: up, down, seg_time
      integer, intent(in) :: repeats
      type(history_type), intent(out) :: hist
      type(error_type), allocatable, intent(out) :: error
      real(dp), allocatable :: t(:), v(:)
      integer :: k
      if (repeats < 1 .or. .not. seg_time > 0.0_dp) then
         call fatal_error(error, 'ratchet needs repeats >= 1 and seg_time > 0')
         return
      end if
      if (repeats > max_points/2) then
         call fatal_error(error, 'ratchet: repeats = '//str(repeats)//' is more than the '// &
                          str(max_points/2)//' a history may have')
         return
      end if
      allocate (t(2*repeats + 1), v(2*repeats + 1))
      t(1) = 0.0_dp
      v(1) = 0.0_dp
      do k = 1, repeats
         t(2*k) = t(2*k - 1) + seg_time
         v(2*k) = v(2*k - 1) + up
         t(2*k + 1) = t(2*k) + seg_time
         v(2*k + 1) = v(2*k) - down
      end do
      call history_from_points(t, v, control_strain, hist, error)
   end subroutine ratchet_history

   !> Constant-amplitude triangular cycling about a mean strain: range (max - min strain),
   !> strain rate (1/s) or period (s), number of cycles, optional holds at the peaks (s).
   !> Each cycle: mean -> max (hold) -> min (hold) -> mean. Starts from zero strain.
   pure subroutine cyclic_history(strain_range, mean, rate, period, cycles, hold_max, hold_min, &
                                  hist, error)
      real(dp), intent(in) :: strain_range, mean, rate, period, hold_max, hold_min
      integer, intent(in) :: cycles
      type(history_type), intent(out) :: hist
      type(error_type), allocatable, intent(out) :: error
      real(dp), allocatable :: t(:), v(:)
      real(dp) :: amp, quarter, tt
      integer :: k, np
      if (.not. strain_range > 0.0_dp .or. cycles < 1) then
         call fatal_error(error, 'cyclic needs strain_range > 0 and cycles >= 1')
         return
      end if
      if (cycles > max_points/8) then
         call fatal_error(error, 'cyclic: cycles = '//str(cycles)//' is more than the '// &
                          str(max_points/8)//' a history may have')
         return
      end if
      if (.not. (hold_max >= 0.0_dp .and. hold_min >= 0.0_dp)) then
         call fatal_error(error, 'cyclic: hold_max and hold_min must be >= 0 (s): hold_max = '// &
                          real_str(hold_max, 'g0.6')//', hold_min = '//real_str(hold_min, 'g0.6'))
         return
      end if
      amp = 0.5_dp*strain_range
      if (rate > 0.0_dp) then
         quarter = amp/rate
      else if (period > 0.0_dp) then
         quarter = 0.25_dp*period
      else
         call fatal_error(error, 'cyclic needs strain_rate > 0 (1/s) or period > 0 (s): strain_rate = '// &
                          real_str(rate, 'g0.6')//', period = '//real_str(period, 'g0.6'))
         return
      end if
      allocate (t(6*cycles + 2), v(6*cycles + 2))
      np = 1
      t(1) = 0.0_dp
      v(1) = 0.0_dp
      tt = 0.0_dp
      if (mean /= 0.0_dp) then
         tt = abs(mean)/(amp/quarter)
         call add_point(t, v, np, tt, mean)
      end if
      do k = 1, cycles
         tt = tt + quarter
         call add_point(t, v, np, tt, mean + amp)
         if (hold_max > 0.0_dp) then
            tt = tt + hold_max
            call add_point(t, v, np, tt, mean + amp)
         end if
         tt = tt + 2.0_dp*quarter
         call add_point(t, v, np, tt, mean - amp)
         if (hold_min > 0.0_dp) then
            tt = tt + hold_min
            call add_point(t, v, np, tt, mean - amp)
         end if
         tt = tt + quarter
         call add_point(t, v, np, tt, mean)
      end do
      call history_from_points(t(:np), v(:np), control_strain, hist, error)
   end subroutine cyclic_history

   pure subroutine add_point(t, v, np, time, val)
      real(dp), intent(inout) :: t(:), v(:)
      integer, intent(inout) :: np
      real(dp), intent(in) :: time, val
      np = np + 1
      t(np) = time
      v(np) = val
   end subroutine add_point

   !> Monotonic tension at a constant strain rate (1/s) to a final strain
   pure subroutine tensile_history(rate, final_strain, hist, error)
      real(dp), intent(in) :: rate, final_strain
      type(history_type), intent(out) :: hist
      type(error_type), allocatable, intent(out) :: error
      if (rate <= 0.0_dp .or. final_strain <= 0.0_dp) then
         call fatal_error(error, 'tensile needs strain_rate > 0 and final_strain > 0')
         return
      end if
      call history_from_points([0.0_dp, final_strain/rate], [0.0_dp, final_strain], &
                               control_strain, hist, error)
   end subroutine tensile_history

   !> Tension with strain-rate jumps: the strain rises by final_strain/size(rates) at each
   !> rate in turn (1/s), so the flow stress's rate sensitivity shows at fixed hardening
   pure subroutine rate_jump_history(rates, final_strain, hist, error)
      real(dp), intent(in) :: rates(:), final_strain
      type(history_type), intent(out) :: hist
      type(error_type), allocatable, intent(out) :: error
      real(dp) :: t(size(rates) + 1), v(size(rates) + 1), de
      integer :: k
      if (size(rates) < 1 .or. any(rates <= 0.0_dp) .or. final_strain <= 0.0_dp) then
         call fatal_error(error, 'rate_jump needs rates > 0 and final_strain > 0')
         return
      end if
      de = final_strain/real(size(rates), dp)
      t(1) = 0.0_dp
      v(1) = 0.0_dp
      do k = 1, size(rates)
         t(k + 1) = t(k) + de/rates(k)
         v(k + 1) = v(k) + de
      end do
      call history_from_points(t, v, control_strain, hist, error)
   end subroutine rate_jump_history

   !> Creep: stress ramped to its value in ramp_time, then held to duration (s, from start)
   pure subroutine creep_history(stress, ramp_time, duration, hist, error)
      real(dp), intent(in) :: stress, ramp_time, duration
      type(history_type), intent(out) :: hist
      type(error_type), allocatable, intent(out) :: error
      if (ramp_time <= 0.0_dp .or. duration <= ramp_time) then
         call fatal_error(error, 'creep needs ramp_time > 0 and duration > ramp_time')
         return
      end if
      call history_from_points([0.0_dp, ramp_time, duration], [0.0_dp, stress, stress], &
                               control_stress, hist, error)
   end subroutine creep_history

   !> The thesis's three tests with their published parameters (spec Section 2):
   !> k = 1 ramping-amplitude LCF, 2 two-level relaxation, 3 ratcheting
   pure subroutine thesis_history(k, hist, error)
      integer, intent(in) :: k
      type(history_type), intent(out) :: hist
      type(error_type), allocatable, intent(out) :: error
      select case (k)
      case (1); call thesis_lcf_history(0.0005_dp, 0.005_dp, 12, 10.0_dp, hist, error)
      case (2); call relaxation_history([0.00075_dp, 0.001_dp], 1.0_dp, [600.0_dp, 600.0_dp], hist, error)
      case (3); call ratchet_history(0.0005_dp, 0.00025_dp, 15, 40.0_dp, hist, error)
      case default; call fatal_error(error, 'the thesis has tests 1 to 3 only')
      end select
   end subroutine thesis_history

   !> Output times: a uniform grid of step dt (s) from the start plus every corner, sorted,
   !> without near-duplicates. dt <= 0 gives the corners only.
   pure function output_times(hist, dt) result(times)
      type(history_type), intent(in) :: hist
      real(dp), intent(in) :: dt
      real(dp), allocatable :: times(:)
      real(dp), allocatable :: buf(:)
      real(dp) :: t0, t1, tg, tol
      integer :: ngrid, i, k, n
      t0 = hist%t(1)
      t1 = hist%end_time()
      tol = 1.0e-9_dp*max(1.0_dp, abs(t1))
      ngrid = 0
      if (dt > 0.0_dp) ngrid = floor((t1 - t0)/dt + 1.0e-9_dp)
      allocate (buf(ngrid + 1 + size(hist%t)))
      n = 0
      k = 1
      ! Merge the grid t0 + i*dt with the sorted corners
      do i = 0, ngrid
         tg = t0 + real(i, dp)*dt
         do while (k <= size(hist%t))
            if (hist%t(k) > tg + tol) exit
            call push_unique(buf, n, hist%t(k), tol)
            k = k + 1
         end do
         call push_unique(buf, n, tg, tol)
      end do
      do while (k <= size(hist%t))
         call push_unique(buf, n, hist%t(k), tol)
         k = k + 1
      end do
      times = buf(:n)
   end function output_times

   !> Append x to buf(1:n) unless it repeats the last entry within tol
   pure subroutine push_unique(buf, n, x, tol)
      real(dp), intent(inout) :: buf(:)
      integer, intent(inout) :: n
      real(dp), intent(in) :: x, tol
      if (n > 0) then
         if (abs(x - buf(n)) <= tol) return
      end if
      n = n + 1
      buf(n) = x
   end subroutine push_unique
end module usharp_history
