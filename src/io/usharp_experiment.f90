!> Measured (or synthetic) test data for a fit, in the model's units, and their linear
!> interpolation onto the simulation's output times
module usharp_experiment
   use usharp_kinds, only: dp
   use usharp_error, only: error_type, fatal_error
   use usharp_strings, only: str, real_str
   use usharp_config, only: test_config
   use usharp_history, only: history_type, control_stress, control_strain
   use usharp_input, only: read_data_columns
   use usharp_input_test, only: max_strain, percent_strain, compared_columns, history_settings, stress_share_side
   use usharp_table, only: merge_repeated_times
   use usharp_units, only: stress_factor
   use usharp_sort, only: median
   implicit none
   private

   public :: experiment_type, load_experiment, interpolate, fits_strain, response_name, check_scale
   public :: measured_times, compare_where_measured, data_note, check_programme

   !> A measured strain's stiffest stretch (the elastic unloading after a reversal, the first
   !> loading) below this share of Young's modulus is a strain column in percent (1/100)
   real(dp), parameter :: min_stiffness_share = 0.1_dp
   !> ... and a median secant above this multiple one in a smaller unit than data_unit says
   !> (MPa read as ksi: 6.9 times; the measured Alloy 617 cycles give medians of 0.67 to 0.99
   !> of E and 4.7 to 6.9 so misread, where their largest secants reach 5.7 from noise)
   real(dp), parameter :: max_stiffness_share = 2.5_dp
   !> A measured strain history whose first stress exceeds this share of its peak starts loaded
   real(dp), parameter :: loaded_start = 0.25_dp
   !> Time in ms: under this share of a data file's rows within the simulated time, and its
   !> times running past this many times the simulated span (a part of a test simulated on
   !> its own, the first 22 s of a 1202 s relaxation, is no slip of unit)
   real(dp), parameter :: min_rows_within = 0.1_dp, ms_span = 300.0_dp

   !> One test's data: time (s), the measured response and optional user weights. The
   !> response is the stress (model unit), or the strain (-) of a stress-controlled test
   type :: experiment_type
      real(dp), allocatable :: t(:)
      real(dp), allocatable :: y(:)
      real(dp), allocatable :: weight(:)  !< only with weighting = 'column'
      integer :: nmerged = 0              !< rows with a repeated time folded into one
      !> Output times left out of the comparison: no sample within half an output interval
      !> (see measured_times)
      integer :: nunmeasured = 0
      !> Output times past an end of the data by less than a sampling interval, not compared
      integer :: nbeyond = 0
      integer :: noutside = 0             !< rows outside the simulated time, not compared
      !> peaks not compared: within the simulated time at no turning point, and beyond it
      integer :: npeaks_left = 0, npeaks_beyond = 0
   end type experiment_type

contains

   !> Read a test's data file (columns, unit, filter as the &test group says); a test that
   !> compares only its cycles' peak stresses has those as its data
   subroutine load_experiment(test, model_units, exp, error)
      type(test_config), intent(in) :: test
      character(len=*), intent(in) :: model_units
      type(experiment_type), intent(out) :: exp
      type(error_type), allocatable, intent(out) :: error
      real(dp), allocatable :: vals(:, :)
      character(len=:), allocatable :: compared(:), cols(:)
      if (.not. test%has_data) then
         ! (the caller names the test)
         call fatal_error(error, "no data_file: nothing to compare "// &
            'its simulation with (usharp simulate simulates it alone)')
         return
      end if
      exp%npeaks_left = test%peaks_left
      exp%npeaks_beyond = test%peaks_beyond
      if (test%target == 'peaks') then
         ! Only the cycles' peak stresses are compared: they are the data
         exp%t = pack(test%tout, test%point_kind /= 0)
         exp%y = pack(test%peak_y, test%point_kind /= 0)*stress_factor(test%data%unit, model_units)
         return
      end if
      if (allocated(test%data_read)) then
         ! Read with the history (history 'data'): time and compared_columns
         vals = test%data_read
         exp%nmerged = test%data_merged
      else
         compared = compared_columns(test, fits_strain(test))
         allocate (character(len=max(len(test%data%time_col), len(compared))) :: cols(1 + size(compared)))
         cols(1) = test%data%time_col
         cols(2:) = compared
         call read_data_columns(test%data, cols, vals, error)
         if (allocated(error)) return
         call merge_repeated_times(vals, test%data%file, exp%nmerged, error)
         if (allocated(error)) return
      end if
      exp%t = vals(:, 1)
      if (fits_strain(test)) then
         exp%y = vals(:, 2)
      else
         exp%y = vals(:, 2)*stress_factor(test%data%unit, model_units)
      end if
      if (test%weighting == 'column') then
         if (any(vals(:, 3) < 0.0_dp)) then
            call fatal_error(error, test%data%file//': weight_column '//test%data%weight_col// &
               ' has a negative weight at row '//str(findloc(vals(:, 3) < 0.0_dp, .true., 1))// &
               ' of the data read; weights must be >= 0')
            return
         end if
         exp%weight = vals(:, 3)
      end if
   end subroutine load_experiment

   !> Data in a wrong unit or column, which a fit would take as they are: a measured strain
   !> beyond 1 (in percent), a stress far from what a metal of Young's modulus youngs (model
   !> unit) shows or rising with the strain far more or less steeply than youngs, a measured
   !> strain history that starts loaded, or rows that lie mostly beyond the simulated (output)
   !> times t and far beyond (time in ms)
   pure subroutine check_scale(test, exp, youngs, model_units, t, error)
      type(test_config), intent(in) :: test
      type(experiment_type), intent(in) :: exp
      real(dp), intent(in) :: youngs, t(:)
      character(len=*), intent(in) :: model_units
      type(error_type), allocatable, intent(out) :: error
      real(dp) :: peak, share, tol, t0, t1, stiff
      real(dp), allocatable :: slopes(:)
      if (test%has_peaks() .and. youngs > 0.0_dp) then
         ! The peak file's stresses, read in the same unit as the data's
         peak = maxval(abs(pack(test%peak_y, test%point_kind /= 0)))*stress_factor(test%data%unit, model_units)
         if (stress_share_side(peak, youngs) /= 0) then
            call fatal_error(error, stress_scale_message(test%peak_file, 'its stresses reach', peak, youngs, &
                                                         model_units, test%data%unit))
            return
         end if
      end if
      if (test%target == 'peaks' .or. size(exp%y) == 0) return
      peak = maxval(abs(exp%y))
      if (fits_strain(test)) then
         if (peak > max_strain) call fatal_error(error, percent_strain(test%data%file, &
                                                                     test%data%strain_col, peak))
      else if (youngs > 0.0_dp .and. peak > 0.0_dp) then
         if (stress_share_side(peak, youngs) /= 0) &
            call fatal_error(error, stress_scale_message(test%data%file, "column '"//test%data%stress_col// &
                                                         "' peaks at", peak, youngs, model_units, test%data%unit))
      end if
      if (allocated(error)) return
      ! A strain in percent below 1 (a test of less than 100 % "strain") passes the check
      ! above; its stiffness tells it: the stress rises a hundred times too slowly with it
      if (.not. fits_strain(test) .and. youngs > 0.0_dp .and. peak > 0.0_dp) then
         ! Each secant spans a strain of at least a fifth of the elastic strain of its stress
         ! change too: a programmed strain that holds while the measured stress, a little
         ! later in time, still rises is no stiffness
         slopes = secants(test%hist, exp%t, exp%y, 0.2_dp*peak, 0.04_dp*peak/youngs, 0.05_dp*peak/youngs)
         if (size(slopes) == 0) slopes = [0.0_dp]
         stiff = maxval(slopes)
         if (stiff > 0.0_dp .and. stiff < min_stiffness_share*youngs) then
            call fatal_error(error, test%data%file//": the stress rises with column '"// &
               test%data%strain_col//"' at most "//real_str(stiff, 'es10.3')//' '//model_units// &
               ' per unit strain, '//real_str(stiff/youngs, 'es8.1')//" of Young's modulus ("// &
               real_str(youngs, 'f0.0')//' '//model_units//'): is the strain in percent? '// &
               '(strain is in mm/mm)')
            return
         end if
         ! The other way the largest secant is no guide (noise, a slip of the extensometer):
         ! the median of the secants is
         stiff = median(slopes)
         if (stiff > max_stiffness_share*youngs) then
            call fatal_error(error, test%data%file//": column '"//test%data%stress_col// &
               "' rises with the strain by "//real_str(stiff, 'es10.3')//' '//model_units// &
               ' per unit strain (the median secant), '//real_str(stiff/youngs, 'f0.1')// &
               " times Young's modulus ("//real_str(youngs, 'f0.0')//' '//model_units// &
               "): is the stress in another unit than data_unit = '"//test%data%unit// &
               "' (MPa read as ksi: 6.9 times), or Young's modulus in a larger one?")
            return
         end if
      end if
      ! A simulation starts unloaded: a measured strain history whose stress starts far from
      ! 0 is a part of a test cut from its start (a filter to cycle 2 alone), which the model
      ! would meet in its virgin state
      if (test%history_kind == 'data' .and. .not. fits_strain(test) .and. peak > 0.0_dp) then
         if (abs(exp%y(1)) > loaded_start*peak) then
            call fatal_error(error, test%data%file//': its stress starts at '//real_str(exp%y(1), 'g0.4')// &
               ' '//model_units//' ('//real_str(100.0_dp*abs(exp%y(1))/peak, 'f0.0')//' % of its peak) at t = '// &
               real_str(exp%t(1), 'g0.6')//' s, where the simulation starts unloaded: select the test from '// &
               'its start (with filter, its first cycle and the others wanted: the gaps between them are '// &
               'cycled through)')
            return
         end if
      end if
      t0 = t(1)
      t1 = t(size(t))
      tol = 1.0e-9_dp*max(1.0_dp, abs(t1))
      share = real(count(exp%t >= t0 - tol .and. exp%t <= t1 + tol), dp)/real(size(exp%t), dp)
      if (share < min_rows_within .and. maxval(exp%t) - t0 > ms_span*(t1 - t0)) &
         call fatal_error(error, test%data%file//': '// &
         real_str(100.0_dp*share, 'f0.1')//' % of its rows lie within the simulated '// &
         real_str(t0, 'es10.3')//' to '//real_str(t1, 'es10.3')//' s (its times run to '// &
         real_str(maxval(exp%t), 'es10.3')//' s): is the time in ms? (a part of a longer test is '// &
         'chosen with filter_column)')
   end subroutine check_scale

   !> The message for stresses (what, of file, with its verb) that peak at peak (model unit), outside the
   !> shares of Young's modulus youngs a metal's test reaches
   pure function stress_scale_message(file, what, peak, youngs, model_units, data_unit) result(text)
      character(len=*), intent(in) :: file, what, model_units, data_unit
      real(dp), intent(in) :: peak, youngs
      character(len=:), allocatable :: text
      text = file//': '//what//' '//real_str(peak, 'es10.3')//' '//model_units//', '// &
             real_str(peak/youngs, 'es8.1')//" of Young's modulus ("//real_str(youngs, 'f0.0')//' '// &
             model_units//'): '//trim(merge('is it a stress in GPa, or another column?', &
                                            'is it a stress in Pa, kPa or psi?        ', &
                                            stress_share_side(peak, youngs) < 0))//" (data_unit = '"//data_unit//"')"
   end function stress_scale_message

   !> The secants |d stress / d strain| of a test over stretches of one direction of the
   !> strain, each from a sample to the first within the next 200 from which the stress has
   !> changed by at least dsig (model unit) and the strain by dmin, stress and strain in the
   !> same direction: Young's modulus or near it where the test loads or unloads
   !> elastically, whatever the noise of the strain (dsig over E is some 1e-4), less where it
   !> flows. A stretch ends where the strain turns back by more than back (a secant across
   !> a reversal measures the loop's width, not a stiffness)
   pure function secants(hist, ts, sig, dsig, dmin, back) result(slope)
      !> the test's strain history (measured or programmed)
      type(history_type), intent(in) :: hist
      !> the measured stress (model unit) at times ts (s)
      real(dp), intent(in) :: ts(:), sig(:)
      real(dp), intent(in) :: dsig, dmin, back
      real(dp), allocatable :: slope(:)
      real(dp) :: eps(size(ts)), d, dmax, found(size(ts))
      integer :: i, j, n
      do i = 1, size(ts)
         eps(i) = hist%value_at(min(max(ts(i), hist%t(1)), hist%t(size(hist%t))))
      end do
      n = 0
      do i = 1, size(ts) - 1
         dmax = 0.0_dp
         do j = i + 1, min(i + 200, size(ts))
            d = abs(eps(j) - eps(i))
            if (d < dmax - back) exit
            dmax = max(dmax, d)
            if (abs(sig(j) - sig(i)) < dsig .or. d < dmin) cycle
            ! A stress that relaxes while the strain holds (or creeps on) is no stiffness
            if ((sig(j) - sig(i))*(eps(j) - eps(i)) > 0.0_dp) then
               n = n + 1
               found(n) = abs(sig(j) - sig(i))/d
            end if
            exit
         end do
      end do
      slope = found(:n)
   end function secants

   !> Which output times t (s, ascending) have a measurement to be compared with, for data
   !> sampled at ts (s, ascending) and an output interval dt (s): those within dt/2 of a
   !> sample. Where the data are sampled at least every dt, every output time is; where more
   !> coarsely (a logger at 10 s against dt_out = 1 s), the others would be compared with
   !> values interpolated between samples, which carry none of the data's noise: the noise
   !> estimate from the residual's second differences falls to nearly 0 and a gap appears
   !> that the data do not hold. Output times past either end of the data by less than one
   !> sampling interval there (or dt) are left out too (a file ending at 6299.7 s, the
   !> history at 6300 s); further out they stay, and the interpolation names the mismatch.
   !> dt = 0 (the history's own points) leaves every time in.
   pure function measured_times(t, ts, dt) result(keep)
      real(dp), intent(in) :: t(:), ts(:), dt
      logical :: keep(size(t))
      real(dp) :: tol, lo_tol, hi_tol
      integer :: i, k, n
      n = size(ts)
      keep = .true.
      if (.not. dt > 0.0_dp .or. n < 2) return
      tol = 1.0e-9_dp*max(1.0_dp, abs(ts(1)), abs(ts(n)))
      lo_tol = max(dt, ts(2) - ts(1))
      hi_tol = max(dt, ts(n) - ts(n - 1))
      k = 1
      do i = 1, size(t)
         if (t(i) < ts(1) - tol) then
            keep(i) = t(i) < ts(1) - lo_tol
         else if (t(i) > ts(n) + tol) then
            keep(i) = t(i) > ts(n) + hi_tol
         else
            do while (k < n - 1)
               if (ts(k + 1) >= t(i)) exit
               k = k + 1
            end do
            keep(i) = min(abs(t(i) - ts(k)), abs(ts(k + 1) - t(i))) <= 0.5_dp*dt + tol
         end if
      end do
   end function measured_times

   !> Leave out of test's compared times (and its points' kinds) those without a measurement
   !> of exp (measured_times; a cycle's peak stays); count them, and exp's rows outside the
   !> simulated time, in exp
   pure subroutine compare_where_measured(test, exp)
      type(test_config), intent(inout) :: test
      type(experiment_type), intent(inout) :: exp
      real(dp), allocatable :: t(:)
      logical, allocatable :: keep(:)
      real(dp) :: tol
      t = test%times()
      if (size(t) == 0 .or. size(exp%t) == 0) return
      tol = 1.0e-9_dp*max(1.0_dp, abs(t(1)), abs(t(size(t))))
      exp%noutside = count(exp%t < t(1) - tol .or. exp%t > t(size(t)) + tol)
      keep = measured_times(t, exp%t, test%dt_out)
      if (test%has_peaks()) keep = keep .or. test%point_kind /= 0
      tol = 1.0e-9_dp*max(1.0_dp, abs(exp%t(1)), abs(exp%t(size(exp%t))))
      exp%nbeyond = count(.not. keep .and. (t < exp%t(1) - tol .or. t > exp%t(size(exp%t)) + tol))
      exp%nunmeasured = count(.not. keep) - exp%nbeyond
      if (all(keep)) return
      test%tout = pack(t, keep)
      if (allocated(test%point_kind)) then
         if (size(test%point_kind) == size(keep)) then
            test%point_kind = pack(test%point_kind, keep)
            test%peak_y = pack(test%peak_y, keep)
            test%peak_cycle = pack(test%peak_cycle, keep)
         end if
      end if
   end subroutine compare_where_measured

   !> What a summary says of how a test's data were compared: rows repeating a time stamp
   !> (averaged into one as the data are read), output times without a measurement and rows
   !> outside the simulated time (neither compared); '' when none. In parentheses after two
   !> spaces, for a summary's line, unless bare
   pure function data_note(exp, dt_out, bare) result(note)
      type(experiment_type), intent(in) :: exp
      real(dp), intent(in) :: dt_out   !< the test's output interval, s
      logical, intent(in), optional :: bare
      character(len=:), allocatable :: note
      note = ''
      if (exp%nmerged > 0) note = note//'; rows repeating a time stamp of the data: '// &
                                  str(exp%nmerged)//', each averaged into the row of that time'
      if (exp%nunmeasured > 0) note = note//'; output times farther than dt_out/2 from every sample (dt_out = '// &
         plain(dt_out)//' s), not compared: '//str(exp%nunmeasured)
      if (exp%nbeyond > 0) note = note//'; output times past an end of the data by less than '// &
                                  'a sampling interval, not compared: '//str(exp%nbeyond)
      if (exp%noutside > 0) note = note//'; rows outside the simulated time, not compared: '// &
                                   str(exp%noutside)
      if (exp%npeaks_left > 0) note = note//'; peaks of the peak file within the simulated time at '// &
                                      'no turning point of the history, not compared: '//str(exp%npeaks_left)
      if (exp%npeaks_beyond > 0) note = note//'; peaks of the peak file beyond the simulated time: '// &
                                        str(exp%npeaks_beyond)
      if (len(note) == 0) return
      note = note(3:)
      if (present(bare)) then
         if (bare) return
      end if
      note = '  ('//note//')'
   contains
      !> x with up to six significant digits and no trailing zeros ('0.5', '1', '5000')
      pure function plain(x) result(text)
         real(dp), intent(in) :: x
         character(len=:), allocatable :: text
         integer :: k
         text = real_str(x, 'g0.6')
         if (index(text, 'E') > 0 .or. index(text, '.') == 0) return
         k = len(text)
         do while (text(k:k) == '0')
            k = k - 1
         end do
         if (text(k:k) == '.') k = k - 1
         text = text(:k)
      end function plain
   end function data_note

   !> A programmed history against the data file's own record of the control it set (its
   !> strain column under strain control, its stress column under stress control), where
   !> the file has that column: a range given where the amplitude was meant, a hold left out
   !> or a rate that is not the test's simulates another test than the one measured, and a
   !> fit of it takes the constants anywhere. An error where, at more than a tenth of the
   !> rows within the history's time, the two differ by more than a fifth of the measured
   !> control's range; histories 'data' and 'file' are the record itself.
   subroutine check_programme(test, model_units, error)
      type(test_config), intent(in) :: test
      character(len=*), intent(in) :: model_units
      type(error_type), allocatable, intent(out) :: error
      real(dp), parameter :: max_share = 0.1_dp, max_diff = 0.2_dp
      real(dp), allocatable :: vals(:, :), prog(:), meas(:), d(:), tin(:)
      type(error_type), allocatable :: unread
      character(len=:), allocatable :: column, cols(:), hint
      logical, allocatable :: inside(:)
      real(dp) :: range, prange, tol
      integer :: k, nbad
      if (.not. test%has_data .or. test%target == 'peaks') return
      if (any(test%history_kind == [character(len=4) :: 'data', 'file'])) return
      if (test%hist%control == control_stress) then
         column = test%data%stress_col
      else
         column = test%data%strain_col
      end if
      allocate (character(len=max(len(column), len(test%data%time_col))) :: cols(2))
      cols(1) = test%data%time_col
      cols(2) = column
      call read_data_columns(test%data, cols, vals, unread)
      ! A file without that column has nothing to check against
      if (allocated(unread)) return
      tol = 1.0e-9_dp*max(1.0_dp, abs(test%hist%end_time()))
      inside = vals(:, 1) >= test%hist%t(1) - tol .and. vals(:, 1) <= test%hist%end_time() + tol
      if (count(inside) < 2) return
      tin = pack(vals(:, 1), inside)
      meas = pack(vals(:, 2), inside)
      if (test%hist%control == control_stress) meas = meas*stress_factor(test%data%unit, model_units)
      prog = [(test%hist%value_at(min(max(tin(k), test%hist%t(1)), test%hist%end_time())), k=1, size(tin))]
      range = maxval(meas) - minval(meas)
      if (.not. range > 0.0_dp) return
      d = abs(prog - meas)
      nbad = count(d > max_diff*range)
      if (real(nbad, dp) <= max_share*real(size(d), dp)) return
      k = maxloc(d, 1)
      ! A strain column in percent spans about a hundred times the programmed fraction
      prange = maxval(prog) - minval(prog)
      hint = ''
      if (test%hist%control == control_strain .and. range > 50.0_dp*prange .and. &
          range < 200.0_dp*prange) hint = '; strain is read as a fraction: is the column in percent?'
      call fatal_error(error, test%data%file//": its column '"//column//"' (from "// &
         real_str(minval(meas), 'g0.4')//' to '//real_str(maxval(meas), 'g0.4')//hint//') and history '''// &
         test%history_kind//''' differ by more than a fifth of that range at '// &
         real_str(100.0_dp*real(nbad, dp)/real(size(d), dp), 'f0.0')//' % of its rows (at t = '// &
         real_str(tin(k), 'g0.6')//' s: '//real_str(prog(k), 'g0.4')//' against '// &
         real_str(meas(k), 'g0.4')//'): do '//history_settings(test%history_kind)// &
         ' describe the test that was run?')
   end subroutine check_programme

   !> A stress-controlled test (creep) is fitted on its strain, the response it measures; an
   !> external command reports stress only
   pure logical function fits_strain(test)
      type(test_config), intent(in) :: test
      fits_strain = test%hist%control == control_stress .and. .not. test%ext%enabled
   end function fits_strain

   !> Name and unit of the fitted response of a test
   pure function response_name(test, model_units) result(text)
      type(test_config), intent(in) :: test
      character(len=*), intent(in) :: model_units
      character(len=:), allocatable :: text
      if (fits_strain(test)) then
         text = 'strain (-)'
      else
         text = 'stress ('//model_units//')'
      end if
   end function response_name

   !> Linear interpolation of (x, y) at the points xi; points outside [x(1), x(n)] by more
   !> than a relative 1e-9 are an error (no extrapolation)
   pure subroutine interpolate(x, y, xi, yi, error)
      real(dp), intent(in) :: x(:), y(:), xi(:)
      real(dp), intent(out) :: yi(:)
      type(error_type), allocatable, intent(out) :: error
      real(dp) :: tol, w
      integer :: i, k, n
      n = size(x)
      tol = 1.0e-9_dp*max(1.0_dp, abs(x(n)))
      if (xi(1) < x(1) - tol .or. xi(size(xi)) > x(n) + tol) then
         call fatal_error(error, 'data cover '//real_str(x(1), 'g0.6')//' to '// &
            real_str(x(n), 'g0.6')//' s but the simulation runs from '// &
            real_str(xi(1), 'g0.6')//' to '//real_str(xi(size(xi)), 'g0.6')//' s')
         ! Far shorter: a time column in minutes or hours is read as seconds
         if (x(n) - x(1) < 0.5_dp*(xi(size(xi)) - xi(1))) error%message = error%message// &
            ' (time is read in s: is the data''s time column in minutes or hours?)'
         return
      end if
      k = 1
      do i = 1, size(xi)
         do while (k < n - 1)
            if (x(k + 1) >= xi(i)) exit
            k = k + 1
         end do
         w = (xi(i) - x(k))/(x(k + 1) - x(k))
         w = min(max(w, 0.0_dp), 1.0_dp)
         yi(i) = (1.0_dp - w)*y(k) + w*y(k + 1)
      end do
   end subroutine interpolate
end module usharp_experiment
