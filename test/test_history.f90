!> Tests of the load-history generators against hand-computed corner points
module test_history
   use testdrive, only: error_type, unittest_type, new_unittest, check, test_failed
   use usharp_kinds, only: dp
   use usharp_error, only: uerror => error_type
   use usharp_history
   use usharp_strings, only: str
   use usharp_forcing, only: measured_history, turning_points, monotone, signal_resolution
   use usharp_cycles, only: gap_filled_history, record_starts, match_peaks, peak_corners
   use usharp_model_miller, only: miller_model, model_setup
   use usharp_simulation, only: solver_options, sim_result
   use usharp_rosenbrock_driver, only: simulate_rosenbrock
   implicit none
   private
   public :: collect_history

contains

   subroutine collect_history(testsuite)
      type(unittest_type), allocatable, intent(out) :: testsuite(:)
      testsuite = [ &
         new_unittest('thesis-lcf-corners', test_lcf), &
         new_unittest('relaxation-corners', test_relax), &
         new_unittest('ratchet-corners', test_ratchet), &
         new_unittest('cyclic-corners-with-holds', test_cyclic), &
         new_unittest('tensile-and-creep', test_tensile_creep), &
         new_unittest('value-between-corners', test_value), &
         new_unittest('output-times-include-corners', test_output_times), &
         new_unittest('time-not-increasing-rejected', test_bad_points), &
         new_unittest('turning-points-with-hysteresis', test_turning), &
         new_unittest('monotone-pools-violators', test_monotone), &
         new_unittest('measured-forcing-noisy-triangle', test_measured), &
         new_unittest('measured-forcing-noise-zero-is-linear', test_measured_raw), &
         new_unittest('measured-forcing-step-test', test_measured_steps), &
         new_unittest('gap-filled-cycle-10-as-continuous', test_gap_fill), &
         new_unittest('gap-fill-smooth-pieces-and-peaks', test_gap_fill_smooth), &
         new_unittest('gap-fill-linear-straight-across', test_gap_linear), &
         new_unittest('peaks-matched-through-a-drift', test_peaks_drift), &
         new_unittest('measured-forcing-hold-logged-slowly', test_measured_hold), &
         new_unittest('gap-time-for-a-hold-logged-slowly', test_gap_time), &
         new_unittest('gap-cycles-rate-too-slow-for-the-gap-refused', test_gap_rate), &
         new_unittest('measured-forcing-relaxation-logged-slowly', test_relax_slow), &
         new_unittest('measured-forcing-rounded-sine-peaks-are-no-holds', test_sine_peaks), &
         new_unittest('measured-forcing-regular-sampling-is-no-rounding', test_regular_grid), &
         new_unittest('measured-forcing-ramp-into-a-hold-logged-ten-times-slower', test_relax_tenfold), &
         new_unittest('measured-forcing-hold-ends-between-slow-samples', test_hold_ends_unsampled), &
         new_unittest('measured-forcing-jittered-sample-times', test_jittered_times), &
         new_unittest('measured-forcing-coarse-sine-curvature-is-no-noise', test_coarse_sine), &
         new_unittest('measured-forcing-hold-at-the-end', test_end_hold), &
         new_unittest('measured-forcing-controller-approach-into-a-slow-hold', test_pid_approach), &
         new_unittest('measured-forcing-reversal-between-samples', test_reversal_between), &
         new_unittest('measured-forcing-hold-ends-inside-regular-steps', test_hold_ends_inside), &
         new_unittest('measured-forcing-hold-at-the-start', test_start_hold)]
   end subroutine collect_history

   subroutine same(error, actual, expected, what)
      type(error_type), allocatable, intent(out) :: error
      real(dp), intent(in) :: actual(:), expected(:)
      character(len=*), intent(in) :: what
      integer :: k
      if (size(actual) /= size(expected)) then
         call test_failed(error, what//': wrong number of corners')
         return
      end if
      do k = 1, size(actual)
         call check(error, actual(k), expected(k), what, thr=1e-12_dp*max(1.0_dp, abs(expected(k))))
         if (allocated(error)) return
      end do
   end subroutine same

   subroutine test_lcf(error)
      type(error_type), allocatable, intent(out) :: error
      type(history_type) :: h
      type(uerror), allocatable :: uerr
      real(dp) :: m
      call thesis_lcf_history(0.0005_dp, 0.005_dp, 12, 10.0_dp, h, uerr)
      call check(error, size(h%t), 25, 'corners: start + 12 peaks + 12 zeros')
      if (allocated(error)) return
      call check(error, h%end_time(), 240.0_dp, 'thesis LCF lasts 240 s')
      if (allocated(error)) return
      m = 10.0_dp**(1.0_dp/11.0_dp)
      ! By hand: +0.0005 at 10 s, 0 at 20 s, -0.0005*m at 30 s, +0.0005*m**2 at 50 s, -0.005 at 230 s
      call same(error, [h%t(2), h%v(2), h%t(3), h%v(3), h%t(4), h%v(4), h%v(6), h%t(24), h%v(24)], &
                [10.0_dp, 0.0005_dp, 20.0_dp, 0.0_dp, 30.0_dp, -0.0005_dp*m, 0.0005_dp*m**2, &
                 230.0_dp, -0.005_dp], 'LCF corners')
   end subroutine test_lcf

   subroutine test_relax(error)
      type(error_type), allocatable, intent(out) :: error
      type(history_type) :: h
      type(uerror), allocatable :: uerr
      call relaxation_history([0.00075_dp, 0.001_dp], 1.0_dp, [600.0_dp, 600.0_dp], h, uerr)
      call same(error, h%t, [0.0_dp, 1.0_dp, 601.0_dp, 602.0_dp, 1202.0_dp], 'relaxation times')
      if (allocated(error)) return
      call same(error, h%v, [0.0_dp, 0.00075_dp, 0.00075_dp, 0.001_dp, 0.001_dp], 'relaxation strains')
   end subroutine test_relax

   subroutine test_ratchet(error)
      type(error_type), allocatable, intent(out) :: error
      type(history_type) :: h
      type(uerror), allocatable :: uerr
      call ratchet_history(0.0005_dp, 0.00025_dp, 15, 40.0_dp, h, uerr)
      call check(error, h%end_time(), 1200.0_dp, 'ratchet lasts 1200 s')
      if (allocated(error)) return
      call check(error, maxval(h%v), 0.004_dp, 'peak strain 0.4 %', thr=1e-15_dp)
      if (allocated(error)) return
      call same(error, h%v(1:5), [0.0_dp, 0.0005_dp, 0.00025_dp, 0.00075_dp, 0.0005_dp], 'first corners')
   end subroutine test_ratchet

   subroutine test_cyclic(error)
      type(error_type), allocatable, intent(out) :: error
      type(history_type) :: h
      type(uerror), allocatable :: uerr
      ! 1 % range at 1e-3/s: quarter cycle 5 s; 30 s hold at the tensile peak; 2 cycles
      call cyclic_history(0.01_dp, 0.0_dp, 1.0e-3_dp, 0.0_dp, 2, 30.0_dp, 0.0_dp, h, uerr)
      call same(error, h%t, [0.0_dp, 5.0_dp, 35.0_dp, 45.0_dp, 50.0_dp, 55.0_dp, 85.0_dp, 95.0_dp, &
                             100.0_dp], 'cyclic times')
      if (allocated(error)) return
      call same(error, h%v, [0.0_dp, 0.005_dp, 0.005_dp, -0.005_dp, 0.0_dp, 0.005_dp, 0.005_dp, &
                             -0.005_dp, 0.0_dp], 'cyclic strains')
      if (allocated(error)) return
      ! Given by period instead of rate: 20 s period gives the same 5 s quarter
      call cyclic_history(0.01_dp, 0.0_dp, 0.0_dp, 20.0_dp, 1, 0.0_dp, 0.0_dp, h, uerr)
      call same(error, h%t, [0.0_dp, 5.0_dp, 15.0_dp, 20.0_dp], 'cyclic by period')
   end subroutine test_cyclic

   subroutine test_tensile_creep(error)
      type(error_type), allocatable, intent(out) :: error
      type(history_type) :: h
      type(uerror), allocatable :: uerr
      call tensile_history(1.0e-4_dp, 0.02_dp, h, uerr)
      call same(error, [h%t, h%v], [0.0_dp, 200.0_dp, 0.0_dp, 0.02_dp], 'tensile')
      if (allocated(error)) return
      call creep_history(15.0_dp, 1.0_dp, 1000.0_dp, h, uerr)
      call check(error, h%control, control_stress, 'creep is stress controlled')
      if (allocated(error)) return
      call same(error, [h%t, h%v], [0.0_dp, 1.0_dp, 1000.0_dp, 0.0_dp, 15.0_dp, 15.0_dp], 'creep')
   end subroutine test_tensile_creep

   subroutine test_value(error)
      type(error_type), allocatable, intent(out) :: error
      type(history_type) :: h
      type(uerror), allocatable :: uerr
      call history_from_points([0.0_dp, 2.0_dp, 6.0_dp], [0.0_dp, 1.0_dp, -1.0_dp], control_strain, h, uerr)
      call same(error, [h%value_at(1.0_dp), h%value_at(2.0_dp), h%value_at(5.0_dp), h%value_at(9.0_dp)], &
                [0.5_dp, 1.0_dp, -0.5_dp, -1.0_dp], 'interpolated values')
   end subroutine test_value

   subroutine test_output_times(error)
      type(error_type), allocatable, intent(out) :: error
      type(history_type) :: h
      type(uerror), allocatable :: uerr
      call history_from_points([0.0_dp, 1.0_dp, 2.5_dp], [0.0_dp, 1.0_dp, 0.0_dp], control_strain, h, uerr)
      call same(error, output_times(h, 1.0_dp), [0.0_dp, 1.0_dp, 2.0_dp, 2.5_dp], 'grid + corners')
      if (allocated(error)) return
      call same(error, output_times(h, 0.0_dp), [0.0_dp, 1.0_dp, 2.5_dp], 'corners only')
   end subroutine test_output_times

   subroutine test_bad_points(error)
      type(error_type), allocatable, intent(out) :: error
      type(history_type) :: h
      type(uerror), allocatable :: uerr
      call history_from_points([0.0_dp, 2.0_dp, 2.0_dp], [0.0_dp, 1.0_dp, 0.0_dp], control_strain, h, uerr)
      call check(error, allocated(uerr), 'repeated time rejected')
      if (allocated(error)) return
      call check(error, index(uerr%message, 'not increasing at point 3') > 0, uerr%message)
   end subroutine test_bad_points

   !> Reversals count once the signal has come back by more than delta: a dip smaller than
   !> that inside a ramp is not a turning point
   subroutine test_turning(error)
      type(error_type), allocatable, intent(out) :: error
      integer, allocatable :: idx(:)
      idx = turning_points([0.0_dp, 1.0_dp, 2.0_dp, 1.8_dp, 3.0_dp, 4.0_dp, 2.0_dp, 0.0_dp, &
                            -1.0_dp, 0.5_dp], 0.5_dp)
      call check(error, size(idx), 4, 'start, peak at 4, valley at -1, end')
      if (allocated(error)) return
      call check(error, all(idx == [1, 6, 9, 10]), 'turning points at samples 1, 6, 9, 10')
   end subroutine test_turning

   !> Pool adjacent violators by hand: [1, 3, 2, 4] rising is [1, 2.5, 2.5, 4]
   subroutine test_monotone(error)
      type(error_type), allocatable, intent(out) :: error
      call same(error, monotone([1.0_dp, 3.0_dp, 2.0_dp, 4.0_dp], .true.), &
                [1.0_dp, 2.5_dp, 2.5_dp, 4.0_dp], 'rising')
      if (allocated(error)) return
      call same(error, monotone([4.0_dp, 2.0_dp, 3.0_dp, 1.0_dp], .false.), &
                [4.0_dp, 2.5_dp, 2.5_dp, 1.0_dp], 'falling')
      if (allocated(error)) return
      call check(error, signal_resolution([0.0_dp, 3.0e-5_dp, 4.0e-5_dp, 4.0e-5_dp]), 1.0e-5_dp, &
                 'smallest non-zero step', thr=1.0e-18_dp)
   end subroutine test_monotone

   !> A step test: triangles of amplitude 5e-4, 1e-3, 2e-3 and 5e-3 at 1e-3/s (0.1 s samples);
   !> its first cycle is a tenth of the range. Recorded to 1e-5 with dips of 7 quanta, the
   !> forcing turns at every peak and nowhere else; unrounded (a simulation's values), it
   !> passes through the samples within 1e-6 of the range
   subroutine test_measured_steps(error)
      type(error_type), allocatable, intent(out) :: error
      type(history_type) :: h
      type(uerror), allocatable :: uerr
      real(dp), parameter :: amp(4) = [5.0e-4_dp, 1.0e-3_dp, 2.0e-3_dp, 5.0e-3_dp]
      real(dp), allocatable :: t(:), v(:), truth(:)
      real(dp) :: val
      integer :: k, j, round, npeak
      t = [0.0_dp]
      truth = [0.0_dp]
      ! each cycle: up to +amp, down to -amp, back to 0
      do j = 1, size(amp)
         do k = 1, nint(4.0_dp*amp(j)/1.0e-4_dp)
            t = [t, t(size(t)) + 0.1_dp]
            val = 1.0e-4_dp*real(k, dp)
            if (val <= amp(j)) then
               truth = [truth, val]
            else if (val <= 3.0_dp*amp(j)) then
               truth = [truth, 2.0_dp*amp(j) - val]
            else
               truth = [truth, val - 4.0_dp*amp(j)]
            end if
         end do
      end do
      npeak = 2*size(amp)
      do round = 1, 2
         if (round == 1) then
            v = 1.0e-5_dp*anint(truth/1.0e-5_dp)
            ! a dip of 7 quanta inside the last ramp up
            k = size(v) - 20
            v(k:k + 1) = v(k:k + 1) - 7.0e-5_dp
         else
            v = truth
         end if
         call measured_history(t, v, control_strain, h, uerr)
         call check(error, .not. allocated(uerr), 'forcing failed')
         if (allocated(error)) return
         call check(error, size(h%stops), npeak + 2, 'turning points: the start, the '// &
                    'peaks and the end')
         if (allocated(error)) return
         if (round == 2) then
            do k = 1, size(t)
               val = h%value_at(t(k))
               call check(error, abs(val - v(k)) <= 1.0e-6_dp*1.0e-2_dp, 'unrounded samples '// &
                          'not followed')
               if (allocated(error)) return
            end do
         end if
      end do
   end subroutine test_measured_steps

   !> Cycles of +-0.5 % at 1e-3/s with 60 s holds at both peaks, sampled every 0.5 s on the
   !> ramps and every 20 s in the holds, rounded to 1e-5 (as loggers record them): the
   !> forcing stays within a resolution step of the command everywhere (a spline through the
   !> holds had swung to 0.75 % within them) and each peak's turning point is where its hold
   !> starts
   subroutine test_measured_hold(error)
      type(error_type), allocatable, intent(out) :: error
      type(history_type) :: cmd, h
      type(uerror), allocatable :: uerr
      integer, allocatable :: idx(:), kind(:)
      real(dp) :: tt
      integer :: k
      call cyclic_history(0.01_dp, 0.0_dp, 1.0e-3_dp, 0.0_dp, 3, 60.0_dp, 60.0_dp, cmd, uerr)
      call check(error, .not. allocated(uerr), 'programmed history')
      if (allocated(error)) return
      call logged_forcing(cmd, h, error)
      if (allocated(error)) return
      call peak_corners(h, idx, kind)
      call check(error, size(idx) >= 5, 'turning points of the forcing: '//str(size(idx)))
      if (allocated(error)) return
      do k = 1, size(idx)
         ! the command arrives at each peak (a multiple of 5 s less the holds before it) and
         ! holds 60 s: the hold starts at the command's first time at the peak's value
         tt = h%t(idx(k))
         call check(error, abs(cmd%value_at(tt) - cmd%value_at(tt - 0.5_dp)) > 1.0e-4_dp, &
                    'turning point at t = '//str(tt)//' s is not where its hold starts')
         if (allocated(error)) return
      end do
   end subroutine test_measured_hold

   !> The same cycles with one sample a minute in the holds: steps longer than 50 times the
   !> median (0.5 s) are gaps, so the hold's samples stand alone between gaps, which is
   !> refused naming them and gap_time; with gap_time = 100 s there is no gap
   subroutine test_gap_time(error)
      type(error_type), allocatable, intent(out) :: error
      type(history_type) :: cmd, h
      type(uerror), allocatable :: uerr
      real(dp), allocatable :: t(:), v(:), spans(:, :)
      integer :: k
      call cyclic_history(0.01_dp, 0.0_dp, 1.0e-3_dp, 0.0_dp, 3, 180.0_dp, 180.0_dp, cmd, uerr)
      t = logged_times(cmd, 60.0_dp)
      allocate (v(size(t)))
      do k = 1, size(t)
         v(k) = cmd%value_at(t(k))
      end do
      call gap_filled_history(t, v, control_strain, 0.0_dp, 0.0_dp, 0.0_dp, h, spans, uerr)
      call check(error, allocated(uerr), 'a lone sample between gaps is refused')
      if (allocated(error)) return
      call check(error, index(uerr%message, 'gap_time') > 0 .and. index(uerr%message, 'alone') > 0, &
                 uerr%message)
      if (allocated(error)) return
      deallocate (uerr)
      call gap_filled_history(t, v, control_strain, 0.0_dp, 0.0_dp, 0.0_dp, h, spans, uerr, gap_time=100.0_dp)
      call check(error, .not. allocated(uerr), 'with gap_time')
      if (allocated(error)) return
      call check(error, size(spans, 2), 1, 'one recorded piece')
      if (allocated(error)) return
      call check(error, abs(h%value_at(t(size(t)) - 1.0_dp) - cmd%value_at(t(size(t)) - 1.0_dp)) < 1.0e-7_dp, &
                 'the last hold followed')
   end subroutine test_gap_time

   !> Cycles of 1 % at 1e-3/s recorded to 40 s and from 180 s: gap cycles stated at 1e-5/s
   !> (a half cycle of 1000 s) cannot fill the 140 s gap and are refused naming it and
   !> strain_rate, where they had been squeezed into it; at 1e-3/s they fill it
   subroutine test_gap_rate(error)
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: uerr
      type(history_type) :: cont, filled
      real(dp), allocatable :: t(:), v(:), spans(:, :)
      integer :: k
      call cycles_with_a_gap(cont, t, v)
      call gap_filled_history(t, v, control_strain, 0.01_dp, 0.0_dp, 1.0e-5_dp, filled, spans, uerr, noise=0.0_dp)
      call check(error, allocated(uerr), 'a rate too slow for the gap refused')
      if (allocated(error)) return
      call check(error, index(uerr%message, 'strain_rate = 1.00E-05 /s') > 0 .and. &
                 index(uerr%message, 'longer than the gap from t = 39.95 to 180.00 s') > 0, uerr%message)
      if (allocated(error)) return
      deallocate (uerr)
      call gap_filled_history(t, v, control_strain, 0.01_dp, 0.0_dp, 1.0e-3_dp, filled, spans, uerr, noise=0.0_dp)
      call check(error, .not. allocated(uerr), 'at 1e-3/s the cycles fill the gap')
   end subroutine test_gap_rate

   !> A relaxation test (a 5 s ramp to 0.5 %, then a 600 s hold, then a ramp to 1 % and a
   !> hold) logged every 0.5 s on the ramps and every 20 s in the holds, rounded to 1e-5:
   !> the holds are not at turning points, and the spline through the samples had swung to
   !> below 0.35 % between them; it stays within 1e-5 of the command everywhere
   subroutine test_relax_slow(error)
      type(error_type), allocatable, intent(out) :: error
      type(history_type) :: cmd, h
      type(uerror), allocatable :: uerr
      call history_from_points([0.0_dp, 5.0_dp, 605.0_dp, 610.0_dp, 1210.0_dp], &
                               [0.0_dp, 5.0e-3_dp, 5.0e-3_dp, 1.0e-2_dp, 1.0e-2_dp], control_strain, cmd, uerr)
      call logged_forcing(cmd, h, error)
   end subroutine test_relax_slow

   !> A sine of 1 % range and 20 s period sampled every 0.02 s and rounded to 1e-5: near
   !> its peaks it stays within the hold band (3 noise scales, 3e-5) for 0.7 s, over 20 times
   !> the time its average ramp rate takes to cross the band, and its peaks had been taken as
   !> holds (each a flat branch from 0.36 s before the peak); a rounded top approaches its
   !> value ever more slowly, a hold does not, so no peak is a hold: one corner at each, at
   !> the last of the samples that share the top value (0.14 s after the peak), and the
   !> forcing within 2.5 resolution steps of the sine (2.1e-5 beside that corner)
   subroutine test_sine_peaks(error)
      type(error_type), allocatable, intent(out) :: error
      type(history_type) :: h
      type(uerror), allocatable :: uerr
      real(dp), parameter :: pi = acos(-1.0_dp)
      real(dp), allocatable :: t(:), v(:)
      integer, allocatable :: idx(:), kind(:)
      real(dp) :: worst, tt, tworst
      integer :: k
      t = [(0.02_dp*k, k=0, 2500)]
      v = 1.0e-5_dp*anint(5.0e-3_dp*sin(2.0_dp*pi*t/20.0_dp)/1.0e-5_dp)
      call measured_history(t, v, control_strain, h, uerr)
      call check(error, .not. allocated(uerr), 'forcing failed')
      if (allocated(error)) return
      call peak_corners(h, idx, kind)
      call check(error, size(idx), 5, 'peaks of 2.5 cycles')
      if (allocated(error)) return
      do k = 1, size(idx)
         tt = h%t(idx(k))
         call check(error, abs(tt - (5.0_dp + 10.0_dp*(k - 1))) <= 0.15_dp, 'peak '//str(k)//' at t = '// &
                    str(tt)//' s, the sine''s at '//str(5.0_dp + 10.0_dp*(k - 1))//' s')
         if (allocated(error)) return
      end do
      worst = 0.0_dp
      tworst = 0.0_dp
      do k = 0, 5000
         tt = 0.01_dp*k
         if (abs(h%value_at(tt) - 5.0e-3_dp*sin(2.0_dp*pi*tt/20.0_dp)) > worst) then
            worst = abs(h%value_at(tt) - 5.0e-3_dp*sin(2.0_dp*pi*tt/20.0_dp))
            tworst = tt
         end if
      end do
      call check(error, worst <= 2.5e-5_dp, 'largest |forcing - sine| '//str(worst)//' > 2.5e-5 at t = '// &
                 str(tworst)//' s')
   end subroutine test_sine_peaks

   !> A triangle of 1 % range at 1e-3/s sampled every 0.5 s from 0.4 s and rounded to
   !> 1e-5: every sample lies on 1e-4, the grid of the sampling itself (steps of 5e-4 along
   !> the ramps, shorter only where a reversal falls between samples), and no rounding shows.
   !> Taken as a quantum, 1e-4 had let the smoother lay each branch straight from its
   !> turning point, 1.9e-4 off the samples after each reversal; the forcing passes through
   !> every sample
   subroutine test_regular_grid(error)
      type(error_type), allocatable, intent(out) :: error
      type(history_type) :: h, cmd
      type(uerror), allocatable :: uerr
      real(dp), allocatable :: t(:), v(:)
      real(dp) :: worst
      integer :: k
      call cyclic_history(0.01_dp, 0.0_dp, 1.0e-3_dp, 0.0_dp, 2, 0.0_dp, 0.0_dp, cmd, uerr)
      call check(error, .not. allocated(uerr), 'programmed history')
      if (allocated(error)) return
      t = [0.0_dp, (0.4_dp + 0.5_dp*k, k=0, 78)]
      call sampled_forcing(cmd, t, 1.0e-5_dp, v, h, error)
      if (allocated(error)) return
      worst = 0.0_dp
      do k = 1, size(t)
         worst = max(worst, abs(h%value_at(t(k)) - v(k)))
      end do
      call check(error, worst <= 1.0e-8_dp, 'largest |forcing - sample| '//str(worst)//' > 1e-8')
   end subroutine test_regular_grid

   !> The thesis's two-level relaxation (a 1 s ramp to 7.5e-4, 600 s held, a ramp to 1e-3,
   !> held) logged every 0.05 s on the ramps and every 0.5 s in the holds, ten times as
   !> long: the spline across the first hold steps after a ramp had swung 5.8e-5 off the
   !> hold where only steps over ten times the fine sampling were looked at between
   !> samples; the forcing stays within 1e-8 of the command
   subroutine test_relax_tenfold(error)
      type(error_type), allocatable, intent(out) :: error
      type(history_type) :: cmd, h
      type(uerror), allocatable :: uerr
      real(dp), allocatable :: t(:), v(:)
      real(dp) :: worst, tworst
      integer :: k
      call history_from_points([0.0_dp, 1.0_dp, 601.0_dp, 602.0_dp, 1202.0_dp], &
                               [0.0_dp, 7.5e-4_dp, 7.5e-4_dp, 1.0e-3_dp, 1.0e-3_dp], control_strain, cmd, uerr)
      call check(error, .not. allocated(uerr), 'programmed history')
      if (allocated(error)) return
      t = [(0.05_dp*k, k=0, 20), (1.0_dp + 0.5_dp*k, k=1, 1200), (601.0_dp + 0.05_dp*k, k=1, 20), &
           (602.0_dp + 0.5_dp*k, k=1, 1200)]
      call sampled_forcing(cmd, t, 0.0_dp, v, h, error)
      if (allocated(error)) return
      call command_gap(h, cmd, 120200, worst, tworst)
      call check(error, worst <= 1.0e-8_dp, 'largest |forcing - command| '//str(worst)//' > 1e-8 at t = '// &
                 str(tworst)//' s')
   end subroutine test_relax_tenfold

   !> A triangle of 1e-3/s to +-5e-3 with 60 s holds at its peaks, logged every 0.5 s from
   !> 0.4 s on the ramps and every 20 s in the holds (at 20.4, 40.4, 60.4 s, ...), rounded to
   !> 1e-5: each hold starts 0.1 s after a ramp's last sample and ends 4.6 s before the
   !> next ramp's first. The forcing had run straight from the last ramp sample to the first
   !> hold sample (15.5 s for 0.1 s of ramp) and from the hold's last into the ramp, and a
   !> hold between two such steps had lost its flatness; it follows the command within 1e-8
   !> everywhere (looked at every 0.01 s), the ramps run at their rate up to the level. So
   !> too where the steps holding the hold's ends are twice the ramps' own, and unrounded
   !> with a hold's first sample a hair short of its level
   subroutine test_hold_ends_unsampled(error)
      type(error_type), allocatable, intent(out) :: error
      type(history_type) :: cmd, h
      type(uerror), allocatable :: uerr
      real(dp), allocatable :: t(:), v(:)
      real(dp) :: worst, tt, tworst
      integer :: k
      call history_from_points([0.0_dp, 5.0_dp, 65.0_dp, 75.0_dp, 135.0_dp, 145.0_dp, 205.0_dp, 210.0_dp], &
                               [0.0_dp, 5.0e-3_dp, 5.0e-3_dp, -5.0e-3_dp, -5.0e-3_dp, 5.0e-3_dp, 5.0e-3_dp, &
                                0.0_dp], control_strain, cmd, uerr)
      call check(error, .not. allocated(uerr), 'programmed history')
      if (allocated(error)) return
      t = [0.0_dp]
      do k = 0, 419
         tt = 0.4_dp + 0.5_dp*k
         ! in a hold only every 20 s
         if (in_hold(tt) .and. abs(modulo(tt - 0.4_dp, 20.0_dp)) > 1.0e-9_dp .and. &
             abs(modulo(tt - 0.4_dp, 20.0_dp) - 20.0_dp) > 1.0e-9_dp) cycle
         t = [t, tt]
      end do
      call sampled_forcing(cmd, t, 1.0e-5_dp, v, h, error)
      if (allocated(error)) return
      call command_gap(h, cmd, 20900, worst, tworst)
      call check(error, worst <= 1.0e-8_dp, 'largest |forcing - command| '//str(worst)//' > 1e-8 at t = '// &
                 str(tworst)//' s')
      if (allocated(error)) return
      ! A trapezoid logged every 0.5 s on its ramps whose holds start and end inside steps of
      ! 1 s, twice the ramps' (the hold's first sample 0.75 s after its start, its last
      ! 0.25 s before its end): left to the spline those had been 1.85e-4 off
      call history_from_points([0.0_dp, 5.0_dp, 65.0_dp, 70.0_dp, 130.0_dp, 135.0_dp], &
                               [0.0_dp, 5.0e-3_dp, 5.0e-3_dp, 0.0_dp, 0.0_dp, 5.0e-3_dp], control_strain, cmd, uerr)
      call check(error, .not. allocated(uerr), 'programmed trapezoid')
      if (allocated(error)) return
      t = [0.0_dp, (0.25_dp + 0.5_dp*k, k=0, 9), 5.75_dp, 25.75_dp, 45.75_dp, 64.75_dp, &
           (65.75_dp + 0.5_dp*k, k=0, 8), 70.75_dp, 90.75_dp, 110.75_dp, 129.75_dp, &
           (130.75_dp + 0.5_dp*k, k=0, 8), 135.0_dp]
      call sampled_forcing(cmd, t, 1.0e-5_dp, v, h, error)
      if (allocated(error)) return
      call command_gap(h, cmd, 13500, worst, tworst)
      call check(error, worst <= 1.0e-8_dp, 'trapezoid: largest |forcing - command| '//str(worst)// &
                 ' > 1e-8 at t = '//str(tworst)//' s')
      if (allocated(error)) return
      ! Unrounded, the hold's first sample 1e-12 short of its level (a controller's approach):
      ! the hold had taken in only the samples at the level exactly
      call sampled_forcing(cmd, t, 0.0_dp, v, h, error)
      if (allocated(error)) return
      v(12) = v(12) - 1.0e-12_dp
      call measured_history(t, v, control_strain, h, uerr)
      call check(error, .not. allocated(uerr), 'forcing of the trapezoid')
      if (allocated(error)) return
      call command_gap(h, cmd, 13500, worst, tworst)
      call check(error, worst <= 1.0e-8_dp, 'unrounded trapezoid: largest |forcing - command| '//str(worst)// &
                 ' > 1e-8 at t = '//str(tworst)//' s')
   contains
      logical function in_hold(x)
         real(dp), intent(in) :: x
         in_hold = (x > 5.0_dp .and. x < 65.0_dp) .or. (x > 75.0_dp .and. x < 135.0_dp) .or. &
                   (x > 145.0_dp .and. x < 205.0_dp)
      end function in_hold
   end subroutine test_hold_ends_unsampled

   !> A triangle of 1e-3/s to +-5e-3 logged every 0.5 s at times jittered by up to 0.2 s
   !> (40 % of the step; stamped to 0.01 s), unrounded: read from second differences of the
   !> values alone, the jitter had been noise of 2e-4 and the forcing smoothed up to 3.4e-4
   !> off the samples; read against the sample times, the ramps are straight, and the
   !> forcing passes within 1e-8 of every sample
   subroutine test_jittered_times(error)
      type(error_type), allocatable, intent(out) :: error
      type(history_type) :: cmd, h
      type(uerror), allocatable :: uerr
      real(dp), allocatable :: t(:), v(:)
      real(dp) :: worst
      integer :: k
      call cyclic_history(0.01_dp, 0.0_dp, 1.0e-3_dp, 0.0_dp, 2, 0.0_dp, 0.0_dp, cmd, uerr)
      call check(error, .not. allocated(uerr), 'programmed history')
      if (allocated(error)) return
      t = [0.0_dp, (anint(100.0_dp*(0.5_dp*k + 0.2_dp*sin(1.7_dp*k)))/100.0_dp, k=1, 79)]
      call sampled_forcing(cmd, t, 0.0_dp, v, h, error)
      if (allocated(error)) return
      worst = 0.0_dp
      do k = 1, size(t)
         worst = max(worst, abs(h%value_at(t(k)) - v(k)))
      end do
      call check(error, worst <= 1.0e-8_dp, 'largest |forcing - sample| '//str(worst)//' > 1e-8')
   end subroutine test_jittered_times

   !> A sine of 1 % range and 10 s period logged every 1 s from 0.5 s (10 samples a period,
   !> a sample on each peak), unrounded: its second differences, (2 pi/10)**2 of its
   !> amplitude, had read as noise of 9.4e-4, the turn hysteresis (12 times that) exceeded
   !> its range and no peak was found (the one rising branch then failed to integrate).
   !> Read from fits of rising degree its noise is 1.1e-7 (what a fit of degree 9 leaves of
   !> the sine): a corner at each of its 8 peaks, the forcing within 3e-7 of every sample
   !> and within 1.1e-4 of the sine between them (at the peaks the branches' natural ends
   !> straighten it by 1.0e-4)
   subroutine test_coarse_sine(error)
      type(error_type), allocatable, intent(out) :: error
      type(history_type) :: h
      type(uerror), allocatable :: uerr
      real(dp), parameter :: pi = acos(-1.0_dp)
      real(dp), allocatable :: t(:), v(:)
      integer, allocatable :: idx(:), kind(:)
      real(dp) :: worst, tt
      integer :: k
      t = [0.0_dp, (0.5_dp + k, k=0, 39), 40.0_dp]
      v = 5.0e-3_dp*sin(2.0_dp*pi*t/10.0_dp)
      call measured_history(t, v, control_strain, h, uerr)
      call check(error, .not. allocated(uerr), 'forcing failed')
      if (allocated(error)) return
      call peak_corners(h, idx, kind)
      call check(error, size(idx), 8, 'peaks of 4 cycles')
      if (allocated(error)) return
      worst = 0.0_dp
      do k = 1, size(t)
         worst = max(worst, abs(h%value_at(t(k)) - v(k)))
      end do
      call check(error, worst <= 3.0e-7_dp, 'largest |forcing - sample| '//str(worst)//' > 3e-7')
      if (allocated(error)) return
      worst = 0.0_dp
      do k = 0, 4000
         tt = 0.01_dp*k
         worst = max(worst, abs(h%value_at(tt) - 5.0e-3_dp*sin(2.0_dp*pi*tt/10.0_dp)))
      end do
      call check(error, worst <= 1.1e-4_dp, 'largest |forcing - sine| '//str(worst)//' > 1.1e-4')
   end subroutine test_coarse_sine

   !> A ramp of 1e-3/s to 5e-3, 60 s held, a ramp back to 0 held to the test's end (100 s),
   !> logged every 0.5 s from 0.4 s on the ramps and every 20 s in the holds, rounded to
   !> 1e-5: the last hold starts 0.1 s after the last ramp sample. After the last turning
   !> point the end was no hold, and the forcing had run straight from that sample to the
   !> hold's first, 10.5 s later (9.9e-5 off the command at the hold's start); it follows
   !> the command within 1e-8
   subroutine test_end_hold(error)
      type(error_type), allocatable, intent(out) :: error
      type(history_type) :: cmd, h
      type(uerror), allocatable :: uerr
      real(dp), allocatable :: t(:), v(:)
      real(dp) :: worst, tt, tworst
      integer :: k
      call history_from_points([0.0_dp, 5.0_dp, 65.0_dp, 70.0_dp, 170.0_dp], &
                               [0.0_dp, 5.0e-3_dp, 5.0e-3_dp, 0.0_dp, 0.0_dp], control_strain, cmd, uerr)
      call check(error, .not. allocated(uerr), 'programmed history')
      if (allocated(error)) return
      t = [0.0_dp]
      do k = 0, 339
         tt = 0.4_dp + 0.5_dp*k
         ! in a hold only every 20 s
         if (in_hold(tt) .and. abs(modulo(tt - 0.4_dp, 20.0_dp)) > 1.0e-9_dp .and. &
             abs(modulo(tt - 0.4_dp, 20.0_dp) - 20.0_dp) > 1.0e-9_dp) cycle
         t = [t, tt]
      end do
      t = [t, 170.0_dp]
      call sampled_forcing(cmd, t, 1.0e-5_dp, v, h, error)
      if (allocated(error)) return
      call command_gap(h, cmd, 17000, worst, tworst)
      call check(error, worst <= 1.0e-8_dp, 'largest |forcing - command| '//str(worst)//' > 1e-8 at t = '// &
                 str(tworst)//' s')
   contains
      logical function in_hold(x)
         real(dp), intent(in) :: x
         in_hold = (x > 5.0_dp .and. x < 65.0_dp) .or. x > 70.0_dp
      end function in_hold
   end subroutine test_end_hold

   !> A ramp of 1e-3/s to 4.5e-3, then a controller's exponential approach to 5e-3 (time
   !> constant 3 s, then 5 s), held to 185 s and ramped back down, logged every 0.5 s on
   !> the ramps and every 20 s in the hold, unrounded: the hold's first samples fall short
   !> of its level (by 6.4e-7 at 3 s; at 5 s by 9.2e-6, 1.7e-7 and 3.1e-9, three
   !> samples). Those samples had been corners of straight pieces, the first 20 s long, and
   !> the forcing 2.8e-4 off the approach (2.0e-4 at 5 s); it follows the approach within 1e-6
   subroutine test_pid_approach(error)
      type(error_type), allocatable, intent(out) :: error
      type(history_type) :: h
      type(uerror), allocatable :: uerr
      real(dp), allocatable :: t(:), v(:)
      real(dp) :: worst, tworst, tt, d
      integer :: k, i
      real(dp), parameter :: taus(2) = [3.0_dp, 5.0_dp]
      t = [(0.5_dp*k, k=0, 9), (24.5_dp + 20.0_dp*k, k=0, 8), (185.5_dp + 0.5_dp*k, k=0, 9)]
      do i = 1, size(taus)
         v = [(approach(t(k), taus(i)), k=1, size(t))]
         call measured_history(t, v, control_strain, h, uerr)
         call check(error, .not. allocated(uerr), 'forcing failed')
         if (allocated(error)) return
         worst = 0.0_dp
         tworst = 0.0_dp
         do k = 0, 19000
            tt = 0.01_dp*k
            d = abs(h%value_at(tt) - approach(tt, taus(i)))
            if (d > worst) then
               worst = d
               tworst = tt
            end if
         end do
         call check(error, worst <= 1.0e-6_dp, 'time constant '//str(taus(i))//' s: largest |forcing - command| '// &
                    str(worst)//' > 1e-6 at t = '//str(tworst)//' s')
         if (allocated(error)) return
      end do
   contains
      pure real(dp) function approach(x, tau) result(y)
         real(dp), intent(in) :: x, tau
         if (x <= 4.5_dp) then
            y = 1.0e-3_dp*x
         else
            y = 5.0e-3_dp - 5.0e-4_dp*exp(-(min(x, 185.0_dp) - 4.5_dp)/tau) - 1.0e-3_dp*max(x - 185.0_dp, 0.0_dp)
         end if
      end function approach
   end subroutine test_pid_approach

   !> A triangle of 1e-3/s to +-5e-3 logged every 0.5 s from 0.2 s (each reversal 0.3 s
   !> after a sample, 0.2 s before the next), then from 0.35 s (0.15 s after, 0.35 s
   !> before), unrounded: the corner had been at the sample nearer the peak, the forcing
   !> 2.0e-4 (then 1.9e-4) short of it; where the lines of the two ramps meet it follows the
   !> command within 1e-8
   subroutine test_reversal_between(error)
      type(error_type), allocatable, intent(out) :: error
      type(history_type) :: cmd, h
      type(uerror), allocatable :: uerr
      real(dp), allocatable :: t(:), v(:)
      real(dp) :: worst, tworst
      real(dp), parameter :: offsets(2) = [0.2_dp, 0.35_dp]
      integer :: k, i
      call cyclic_history(0.01_dp, 0.0_dp, 1.0e-3_dp, 0.0_dp, 2, 0.0_dp, 0.0_dp, cmd, uerr)
      call check(error, .not. allocated(uerr), 'programmed history')
      if (allocated(error)) return
      do i = 1, size(offsets)
         t = [0.0_dp, (offsets(i) + 0.5_dp*k, k=0, 79), 40.0_dp]
         t = pack(t, t <= 40.0_dp)
         call sampled_forcing(cmd, t, 0.0_dp, v, h, error)
         if (allocated(error)) return
         call command_gap(h, cmd, 4000, worst, tworst)
         call check(error, worst <= 1.0e-8_dp, 'first sample at '//str(offsets(i))//' s: largest |forcing - command| '// &
                    str(worst)//' > 1e-8 at t = '//str(tworst)//' s')
         if (allocated(error)) return
      end do
   end subroutine test_reversal_between

   !> A trapezoid of 1e-3/s to +-5e-3 with 60 s holds, logged every 0.5 s from 0.25 s
   !> throughout, unrounded: each hold starts and ends 0.25 s into a step of the ramps' own
   !> sampling. Left to the spline those corners had been cut, 1.0e-4 off the command; where
   !> the ramps' lines meet the holds' levels the forcing follows it within 1e-8
   subroutine test_hold_ends_inside(error)
      type(error_type), allocatable, intent(out) :: error
      type(history_type) :: cmd, h
      type(uerror), allocatable :: uerr
      real(dp), allocatable :: t(:), v(:)
      real(dp) :: worst, tworst
      integer :: k
      call history_from_points([0.0_dp, 5.0_dp, 65.0_dp, 75.0_dp, 135.0_dp, 140.0_dp], &
                               [0.0_dp, 5.0e-3_dp, 5.0e-3_dp, -5.0e-3_dp, -5.0e-3_dp, 0.0_dp], control_strain, cmd, uerr)
      call check(error, .not. allocated(uerr), 'programmed trapezoid')
      if (allocated(error)) return
      t = [0.0_dp, (0.25_dp + 0.5_dp*k, k=0, 279), 140.0_dp]
      call sampled_forcing(cmd, t, 0.0_dp, v, h, error)
      if (allocated(error)) return
      call command_gap(h, cmd, 14000, worst, tworst)
      call check(error, worst <= 1.0e-8_dp, 'largest |forcing - command| '//str(worst)//' > 1e-8 at t = '// &
                 str(tworst)//' s')
   end subroutine test_hold_ends_inside

   !> A test that rests at zero strain for 60.2 s, then ramps at 1e-3/s to 5e-3, holds it
   !> 60 s and ramps back, logged every 20 s at rest and in the hold and every 0.5 s on the
   !> ramps (the rest's last sample 0.2 s before the first ramp starts), unrounded: one
   !> spline from the first sample had cut the corner where the rest ends, 1.0e-4 off the
   !> command; as a hold the rest ends where the ramp's line meets it, within 1e-8
   subroutine test_start_hold(error)
      type(error_type), allocatable, intent(out) :: error
      type(history_type) :: cmd, h
      type(uerror), allocatable :: uerr
      real(dp), allocatable :: t(:), v(:)
      real(dp) :: worst, tworst
      integer :: k
      call history_from_points([0.0_dp, 60.2_dp, 65.2_dp, 125.2_dp, 130.2_dp], &
                               [0.0_dp, 0.0_dp, 5.0e-3_dp, 5.0e-3_dp, 0.0_dp], control_strain, cmd, uerr)
      call check(error, .not. allocated(uerr), 'programmed history')
      if (allocated(error)) return
      t = [0.0_dp, 20.0_dp, 40.0_dp, 60.0_dp, (60.5_dp + 0.5_dp*k, k=0, 9), 85.0_dp, 105.0_dp, 125.0_dp, &
           (125.5_dp + 0.5_dp*k, k=0, 9), 130.2_dp]
      call sampled_forcing(cmd, t, 0.0_dp, v, h, error)
      if (allocated(error)) return
      call command_gap(h, cmd, 13020, worst, tworst)
      call check(error, worst <= 1.0e-8_dp, 'largest |forcing - command| '//str(worst)//' > 1e-8 at t = '// &
                 str(tworst)//' s')
   end subroutine test_start_hold

   !> The largest |h - cmd| (worst) and where (tworst, s), looked at every 0.01 s from 0 to
   !> n hundredths of a second
   subroutine command_gap(h, cmd, n, worst, tworst)
      type(history_type), intent(in) :: h, cmd
      integer, intent(in) :: n
      real(dp), intent(out) :: worst, tworst
      real(dp) :: tt
      integer :: k
      worst = 0.0_dp
      tworst = 0.0_dp
      do k = 0, n
         tt = 0.01_dp*k
         if (abs(h%value_at(tt) - cmd%value_at(tt)) > worst) then
            worst = abs(h%value_at(tt) - cmd%value_at(tt))
            tworst = tt
         end if
      end do
   end subroutine command_gap

   !> v: cmd sampled at the times t and rounded to q (0: not rounded); h: its forcing
   subroutine sampled_forcing(cmd, t, q, v, h, error)
      type(history_type), intent(in) :: cmd
      real(dp), intent(in) :: t(:), q
      real(dp), allocatable, intent(out) :: v(:)
      type(history_type), intent(out) :: h
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: uerr
      integer :: k
      allocate (v(size(t)))
      do k = 1, size(t)
         v(k) = cmd%value_at(t(k))
         if (q > 0.0_dp) v(k) = q*anint(v(k)/q)
      end do
      call measured_history(t, v, control_strain, h, uerr)
      call check(error, .not. allocated(uerr), 'forcing failed')
   end subroutine sampled_forcing

   !> h: the forcing of cmd as a logger records it (every 0.5 s, every 20 s in a hold,
   !> rounded to 1e-5), which must stay within 1e-5 of cmd everywhere (looked at every 0.1 s)
   subroutine logged_forcing(cmd, h, error)
      type(history_type), intent(in) :: cmd
      type(history_type), intent(out) :: h
      type(error_type), allocatable, intent(out) :: error
      real(dp), allocatable :: t(:), v(:)
      real(dp) :: worst
      integer :: k
      t = logged_times(cmd, 20.0_dp)
      call sampled_forcing(cmd, t, 1.0e-5_dp, v, h, error)
      if (allocated(error)) return
      worst = 0.0_dp
      do k = 0, nint(10.0_dp*cmd%end_time())
         worst = max(worst, abs(h%value_at(0.1_dp*k) - cmd%value_at(0.1_dp*k)))
      end do
      call check(error, worst <= 1.0e-5_dp, 'largest |forcing - command| '//str(worst)//' > 1e-5')
   end subroutine logged_forcing

   !> Ten cycles of 1 % at 1e-3/s (cont) sampled every 0.05 s to 40 s and from 180 s to
   !> 200 s: one gap of 140 s
   subroutine cycles_with_a_gap(cont, t, v)
      type(history_type), intent(out) :: cont
      real(dp), allocatable, intent(out) :: t(:), v(:)
      type(uerror), allocatable :: uerr
      integer :: k
      call cyclic_history(0.01_dp, 0.0_dp, 1.0e-3_dp, 0.0_dp, 10, 0.0_dp, 0.0_dp, cont, uerr)
      t = [(0.05_dp*k, k=0, 799), (0.05_dp*k, k=3600, 3999)]
      allocate (v(size(t)))
      do k = 1, size(t)
         v(k) = cont%value_at(t(k))
      end do
   end subroutine cycles_with_a_gap

   !> The times a logger records cmd at: every 0.5 s, every hold_step (s) in a hold (where
   !> the command stays put over the next 0.5 s and the next hold_step)
   function logged_times(cmd, hold_step) result(t)
      type(history_type), intent(in) :: cmd
      real(dp), intent(in) :: hold_step
      real(dp), allocatable :: t(:)
      real(dp) :: tt
      t = [0.0_dp]
      do while (t(size(t)) < cmd%end_time() - 1.0e-9_dp)
         tt = t(size(t))
         if (abs(cmd%value_at(tt + 0.5_dp) - cmd%value_at(tt)) < 1.0e-12_dp .and. &
             abs(cmd%value_at(min(tt + hold_step, cmd%end_time())) - cmd%value_at(tt)) < 1.0e-12_dp) then
            t = [t, min(tt + hold_step, cmd%end_time())]
         else
            t = [t, min(tt + 0.5_dp, cmd%end_time())]
         end if
      end do
   end function logged_times

   !> A triangle of strain (amplitude 0.005, 0.1 s samples) rounded to 1e-5 with a dip of
   !> 5e-5 in a ramp: the forcing stops at the two turning points only, stays within two
   !> resolution steps of the true triangle, its ramps are monotone (the dip gone) and its
   !> rate is the command's 1e-3/s along the ramps
   subroutine test_measured(error)
      type(error_type), allocatable, intent(out) :: error
      type(history_type) :: h
      type(uerror), allocatable :: uerr
      real(dp) :: t(201), v(201), truth, val, rate, worst, prev
      integer :: k
      do k = 1, 201
         t(k) = 0.1_dp*real(k - 1, dp)
         truth = merge(1.0e-3_dp*t(k), 1.0e-2_dp - 1.0e-3_dp*t(k), t(k) <= 5.0_dp)
         v(k) = 1.0e-5_dp*anint(truth/1.0e-5_dp)
      end do
      v(21:23) = v(21:23) - 5.0e-5_dp
      call measured_history(t, v, control_strain, h, uerr)
      call check(error, .not. allocated(uerr), 'built')
      if (allocated(error)) return
      call check(error, h%smooth(), 'a smooth forcing')
      if (allocated(error)) return
      call check(error, all(h%corners() == [1, 51, 201]), 'corners: start, peak, end')
      if (allocated(error)) return
      worst = 0.0_dp
      prev = -1.0_dp
      do k = 1, 500
         val = h%value_at(0.01_dp*real(k, dp))
         worst = max(worst, abs(val - 1.0e-3_dp*0.01_dp*real(k, dp)))
         if (val < prev - 1.0e-12_dp) call test_failed(error, 'rising ramp not monotone at '// &
                                                        'sample of 0.01 s '//'x')
         if (allocated(error)) return
         prev = val
      end do
      call check(error, worst <= 2.0e-5_dp, 'within two resolution steps of the triangle')
      if (allocated(error)) return
      call spline_eval(h%tk, h%vk, h%d2, 1, size(h%tk), 2.5_dp, val, rate)
      call check(error, rate, 1.0e-3_dp, 'rate along the ramp', thr=1.0e-4_dp)
      if (allocated(error)) return
      ! Knots where the signal bends only: the ramps need few, whatever the sampling
      call check(error, size(h%tk) <= 20, 'few knots ('//str(size(h%tk))//' of 201 samples)')
      if (allocated(error)) return
      call check(error, all(h%tk(h%kstops) == t([1, 51, 201])), 'the corners are knots')
      if (allocated(error)) return
      do k = 1, 201
         call check(error, h%v(k), h%value_at(t(k)), 'sample '//str(k)//' on the spline', &
                    thr=1.0e-12_dp)
         if (allocated(error)) return
      end do
   end subroutine test_measured

   !> noise = 0 keeps every sample as a corner of a piecewise-linear history
   subroutine test_measured_raw(error)
      type(error_type), allocatable, intent(out) :: error
      type(history_type) :: h
      type(uerror), allocatable :: uerr
      call measured_history([0.0_dp, 1.0_dp, 2.0_dp, 3.0_dp], [0.0_dp, 1.0_dp, 0.5_dp, 2.0_dp], &
                            control_strain, h, uerr, noise=0.0_dp)
      call check(error, .not. h%smooth(), 'piecewise linear')
      if (allocated(error)) return
      call same(error, h%v, [0.0_dp, 1.0_dp, 0.5_dp, 2.0_dp], 'samples kept')
   end subroutine test_measured_raw

   !> Cycles 1, 2 and 10 of a triangular strain cycling (range 1 %, 1e-3/s, 20 s a cycle,
   !> sampled every 0.05 s; the recorded pieces end one sample short of the next cycle, as a
   !> test machine's files do), the gap filled with cycles: the history equals the continuous
   !> 10-cycle one everywhere (so 7 cycles were cycled through), and the simulated stress of
   !> cycle 10 equals that of the continuous simulation
   subroutine test_gap_fill(error)
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: uerr
      type(history_type) :: cont, filled
      type(miller_model) :: model
      type(solver_options) :: opts
      type(sim_result) :: r1, r2
      real(dp), allocatable :: t(:), v(:), spans(:, :), probe(:), t10(:)
      integer :: k
      call cycles_with_a_gap(cont, t, v)
      call check(error, size(record_starts(t, 0.0_dp)), 2, 'one gap found')
      if (allocated(error)) return
      call gap_filled_history(t, v, 1, 0.0_dp, 0.0_dp, 0.0_dp, filled, spans, uerr, noise=0.0_dp)
      if (allocated(uerr)) then
         call test_failed(error, uerr%message)
         return
      end if
      call check(error, .not. filled%smooth(), 'noise 0: piecewise linear')
      if (allocated(error)) return
      call same(error, reshape(spans, [4]), [0.0_dp, 39.95_dp, 180.0_dp, 199.95_dp], 'recorded spans')
      if (allocated(error)) return
      ! The continuous history's corners and points in between, compared with the filled one
      probe = [cont%t(:size(cont%t) - 1), 0.5_dp*(cont%t(2:) + cont%t(:size(cont%t) - 1)), 41.234_dp, 177.7_dp]
      do k = 1, size(probe)
         call check(error, filled%value_at(probe(k)), cont%value_at(probe(k)), &
                    'filled history at t = '//real_str(probe(k)), thr=1.0e-12_dp)
         if (allocated(error)) return
      end do
      call model_setup(model, uerr)
      ! Tight tolerances: the two differ in their steps (every sample of the recorded pieces
      ! is a corner), not in their load
      opts%rtol = 1.0e-9_dp
      opts%atol_strain = 1.0e-12_dp
      t10 = [(180.0_dp + 0.25_dp*k, k=0, 79)]
      call simulate_rosenbrock(model, cont, t10, opts, r1, uerr)
      if (.not. allocated(uerr)) call simulate_rosenbrock(model, filled, t10, opts, r2, uerr)
      if (allocated(uerr)) then
         call test_failed(error, uerr%message)
         return
      end if
      call check(error, maxval(abs(r1%stress - r2%stress)) < 1.0e-6_dp*maxval(abs(r1%stress)), &
                 'cycle 10 stress as in the continuous simulation: largest difference '// &
                 real_str(maxval(abs(r1%stress - r2%stress))))
      if (allocated(error)) return
      ! A cycle less would leave the drag stress elsewhere: the check can fail
      call check(error, abs(r1%drag(1) - r2%drag(1)) < 1.0e-4_dp*r1%drag(1), 'drag stress at cycle 10')
   contains
      function real_str(x) result(text)
         real(dp), intent(in) :: x
         character(len=24) :: text
         write (text, '(g0.6)') x
      end function real_str
   end subroutine test_gap_fill

   !> The same cycling recorded noisily (quantised to 1e-5) as smooth pieces: the fill's
   !> corners are the peaks of the 7 unrecorded cycles at their times within a sample, and the
   !> peaks of cycles 1 to 10 (maxima and minima) are matched to the simulated cycles 1 to 10
   subroutine test_gap_fill_smooth(error)
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: uerr
      type(history_type) :: filled
      real(dp), allocatable :: t(:), v(:), spans(:, :), tp(:)
      integer, allocatable :: kp(:), corner(:), cyc(:)
      integer :: k
      call noisy_recording(t, v)
      call gap_filled_history(t, v, 1, 0.0_dp, 0.0_dp, 0.0_dp, filled, spans, uerr)
      if (allocated(uerr)) then
         call test_failed(error, uerr%message)
         return
      end if
      call check(error, filled%smooth(), 'smooth pieces')
      if (allocated(error)) return
      ! Peaks of cycles 3 to 9: +0.005 at 45, 65, ..., 165 s, -0.005 at 55, ..., 175 s
      do k = 3, 9
         call check(error, filled%value_at(20.0_dp*k - 15.0_dp), 0.005_dp, 'fill maximum', thr=1.0e-9_dp)
         if (allocated(error)) return
         call check(error, filled%value_at(20.0_dp*k - 5.0_dp), -0.005_dp, 'fill minimum', thr=1.0e-9_dp)
         if (allocated(error)) return
      end do
      ! Measured peaks of cycles 1 to 11 (11 lies beyond the history), the maxima 0.3 s early
      tp = [(20.0_dp*k - 15.3_dp, k=1, 11), (20.0_dp*k - 5.0_dp, k=1, 11)]
      kp = [spread(1, 1, 11), spread(-1, 1, 11)]
      call match_peaks(filled, tp, kp, corner, cyc)
      call check(error, all(cyc == [(k, k=1, 10), 0, (k, k=1, 10), 0]), 'cycles 1 to 10 matched')
      if (allocated(error)) return
      do k = 1, 10
         call check(error, filled%t(corner(k)), 20.0_dp*k - 15.0_dp, 'maximum of cycle k', thr=0.051_dp)
         if (allocated(error)) return
      end do
   end subroutine test_gap_fill_smooth

   !> gap_fill = 'linear': the same noisy recording, each gap a straight line from the end of
   !> one smoothed piece to the start of the next, with no cycles in it (one spline over all
   !> samples had bulged across the gap)
   subroutine test_gap_linear(error)
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: uerr
      type(history_type) :: joined
      real(dp), allocatable :: t(:), v(:), spans(:, :)
      real(dp) :: ta, tb, va, vb, tm
      integer :: k
      call noisy_recording(t, v)
      call gap_filled_history(t, v, 1, 0.0_dp, 0.0_dp, 0.0_dp, joined, spans, uerr, straight=.true.)
      if (allocated(uerr)) then
         call test_failed(error, uerr%message)
         return
      end if
      ta = 39.95_dp
      tb = 180.0_dp
      va = joined%value_at(ta)
      vb = joined%value_at(tb)
      call check(error, abs(va - v(800)) < 2.0e-5_dp .and. abs(vb - v(801)) < 2.0e-5_dp, &
                 'the gap starts and ends at the recorded samples')
      if (allocated(error)) return
      do k = 1, 9
         tm = ta + 0.1_dp*k*(tb - ta)
         call check(error, joined%value_at(tm), va + 0.1_dp*k*(vb - va), 'straight across the gap', &
                    thr=1.0e-9_dp)
         if (allocated(error)) return
      end do
      ! The recorded cycles as before: the peaks of cycle 10
      call check(error, joined%value_at(185.0_dp), 0.005_dp, 'cycle 10 maximum', thr=2.0e-5_dp)
   end subroutine test_gap_linear

   !> Measured peaks whose period differs from the simulated cycles' by 0.1 % (0.02 s a cycle
   !> of 20 s, as gap-filled cycles at an interpolated period do): after 400 cycles they lie
   !> 8 s off, more than the quarter cycle within which a peak is matched to its nearest
   !> turning point, and are still matched, each to its own cycle, by following the drift
   subroutine test_peaks_drift(error)
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: uerr
      type(history_type) :: cont
      real(dp), allocatable :: tp(:)
      integer, allocatable :: kp(:), corner(:), cyc(:)
      integer :: k
      call cyclic_history(0.01_dp, 0.0_dp, 1.0e-3_dp, 0.0_dp, 400, 0.0_dp, 0.0_dp, cont, uerr)
      tp = [(20.0_dp*k - 15.0_dp + 0.02_dp*(k - 1), k=1, 400)]
      kp = spread(1, 1, 400)
      call match_peaks(cont, tp, kp, corner, cyc)
      call check(error, all(cyc == [(k, k=1, 400)]), 'maxima matched to their cycles: '// &
                 str(count(cyc == [(k, k=1, 400)]))//' of 400')
   end subroutine test_peaks_drift

   !> Cycles 1, 2 and 10 of a triangular strain cycling (range 1 %, 1e-3/s, sampled every
   !> 0.05 s) recorded to 1e-5, as a test machine's file holds them
   subroutine noisy_recording(t, v)
      real(dp), allocatable, intent(out) :: t(:), v(:)
      type(history_type) :: cont
      call cycles_with_a_gap(cont, t, v)
      v = 1.0e-5_dp*nint(1.0e5_dp*v)
   end subroutine noisy_recording
end module test_history
