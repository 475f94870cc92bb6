!> Measured (or synthetic) test data for a fit, in the model's units, and their linear
!> interpolation onto the simulation's output times
module usharp_experiment
   use usharp_kinds, only: dp
   use usharp_error, only: error_type, fatal_error
   use usharp_strings, only: str, real_str
   use usharp_config, only: test_config
   use usharp_history, only: control_stress
   use usharp_input, only: read_data_columns
   use usharp_input_test, only: max_strain, percent_strain, compared_columns
   use usharp_table, only: merge_repeated_times
   use usharp_units, only: stress_factor
   implicit none
   private

   public :: experiment_type, load_experiment, interpolate, fits_strain, response_name, check_scale

   !> The stress a test's data may peak at, as a share of Young's modulus: below, a column in
   !> GPa (0.35 for 350 MPa) or a strain column; above, one in Pa or kPa
   real(dp), parameter :: min_stress_share = 1.0e-5_dp, max_stress_share = 0.05_dp
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
         call fatal_error(error, "test '"//test%name//"' has no data_file: nothing to compare "// &
            'its simulation with (usharp simulate simulates it alone)')
         return
      end if
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
   !> unit) shows, or rows that lie mostly beyond the simulated times t0 to t1 (s) and far
   !> beyond (time in ms)
   pure subroutine check_scale(test, exp, youngs, model_units, t0, t1, error)
      type(test_config), intent(in) :: test
      type(experiment_type), intent(in) :: exp
      real(dp), intent(in) :: youngs, t0, t1
      character(len=*), intent(in) :: model_units
      type(error_type), allocatable, intent(out) :: error
      real(dp) :: peak, share, tol
      if (test%target == 'peaks' .or. size(exp%y) == 0) return
      peak = maxval(abs(exp%y))
      if (fits_strain(test)) then
         if (peak > max_strain) call fatal_error(error, percent_strain(test%data%file, &
                                                                     test%data%strain_col, peak))
      else if (youngs > 0.0_dp .and. peak > 0.0_dp) then
         if (peak < min_stress_share*youngs .or. peak > max_stress_share*youngs) &
            call fatal_error(error, test%data%file//": column '"//test%data%stress_col// &
            "' peaks at "//real_str(peak, 'es10.3')//' '//model_units//', '// &
            real_str(peak/youngs, 'es8.1')//" of Young's modulus ("//real_str(youngs, 'f0.0')// &
            ' '//model_units//'): '//trim(merge('is it a stress in GPa, or another column?', &
                                                'is it a stress in Pa or kPa?             ', &
                                                peak < min_stress_share*youngs))//' (data_unit = '''// &
            test%data%unit//''')')
      end if
      if (allocated(error)) return
      tol = 1.0e-9_dp*max(1.0_dp, abs(t1))
      share = real(count(exp%t >= t0 - tol .and. exp%t <= t1 + tol), dp)/real(size(exp%t), dp)
      if (share < min_rows_within .and. maxval(exp%t) - t0 > ms_span*(t1 - t0)) &
         call fatal_error(error, test%data%file//': '// &
         real_str(100.0_dp*share, 'f0.1')//' % of its rows lie within the simulated '// &
         real_str(t0, 'es10.3')//' to '//real_str(t1, 'es10.3')//' s (its times run to '// &
         real_str(maxval(exp%t), 'es10.3')//' s): is the time in ms? (a part of a longer test is '// &
         'chosen with filter_column)')
   end subroutine check_scale

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
