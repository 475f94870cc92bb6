!> The &test groups, one per test: its load history, output interval, measured data and
!> weighting, and the external program that simulates it instead of the internal integrator
module usharp_input_test
   use usharp_kinds, only: dp
   use usharp_error, only: error_type, fatal_error, prefix_error
   use usharp_strings, only: lower_text => lower, str, real_str
   use usharp_history, only: history_type, control_strain, control_stress, history_from_points, max_points, &
                             thesis_lcf_history, relaxation_history, ratchet_history, &
                             cyclic_history, tensile_history, creep_history, rate_jump_history, &
                             add_tmf_temperature, output_times
   use usharp_cycles, only: gap_filled_history, match_peaks
   use usharp_sort, only: order_of
   use usharp_table, only: read_columns, merge_repeated_times, numbers_format
   use usharp_simulation, only: solver_options
   use usharp_namelist, only: nml_file, group_text, check_length, read_error, value_len, max_list, unset, &
                              resolve_path
   implicit none
   private

   public :: test_config, data_spec, external_spec, read_test_groups, write_test_defaults
   public :: read_data_columns, max_strain, percent_strain, compared_columns, history_settings
   public :: test_increments, stress_share_side

   !> Longest filter value (a text in a data file's filter column)
   integer, parameter :: filter_len = 128
   !> The largest measured strain (mm/mm) a test driven by it may reach: Alloy 617's tensile
   !> test ends at 0.62; a column in percent of a 1.5 % test reaches 1.5
   real(dp), parameter :: max_strain = 1.0_dp
   !> The stress a test may peak at, as a share of Young's modulus: below, a stress in GPa
   !> (0.35 for 350 MPa) or a strain; above, one in Pa or kPa (see stress_share_side)
   real(dp), parameter :: min_stress_share = 1.0e-5_dp, max_stress_share = 0.05_dp
   !> Relative slack at those bounds, for the rounding of a stress given at one of them
   real(dp), parameter :: bound_slack = 1.0e-9_dp
   !> Largest strain (mm/mm) of a commanded push-pull cycle: a specimen buckles before
   real(dp), parameter :: max_cycle_strain = 0.1_dp

   !> Where a test's measured data come from and how to read them
   type :: data_spec
      character(len=:), allocatable :: file         !< path (relative to the namelist file)
      character(len=:), allocatable :: time_col     !< column name or position
      character(len=:), allocatable :: stress_col
      character(len=:), allocatable :: strain_col
      character(len=:), allocatable :: weight_col   !< optional user weight column
      character(len=:), allocatable :: unit         !< stress unit of the file: ksi or MPa
      character(len=:), allocatable :: filter_col   !< optional row filter column
      character(len=filter_len), allocatable :: filter_values(:)
      character(len=:), allocatable :: format       !< optional Fortran format for fixed files
   end type data_spec

   !> How a test is simulated by an external program (an FE code in batch mode) instead of
   !> the internal integrator: the command, what it writes, and the constants file it reads
   type :: external_spec
      logical :: enabled = .false.                     !< backend = 'external'
      character(len=:), allocatable :: command         !< shell command, placeholders {work} ...
      character(len=:), allocatable :: output_file     !< written by the command in its work folder
      character(len=:), allocatable :: output_format   !< prvar or columns
      character(len=:), allocatable :: time_title      !< column title (or position) of time, s
      character(len=:), allocatable :: stress_title    !< column title (or position) of stress
      character(len=:), allocatable :: unit            !< stress unit of the output: ksi or MPa
      character(len=:), allocatable :: constants_file  !< name of the constants file in the work folder
      character(len=:), allocatable :: constants_format !< Fortran format of one constant, (E12.5)
      real(dp) :: time_limit = 3600.0_dp               !< s, then the command is killed
   end type external_spec

   !> The longest test name (reports hold names in fields of this length)
   integer, parameter, public :: name_len = 128

   !> One test: its load history, output interval and (for fits) its data and weighting
   type :: test_config
      character(len=:), allocatable :: name
      character(len=:), allocatable :: history_kind
      type(history_type) :: hist
      real(dp) :: dt_out = 1.0_dp           !< output interval, s
      real(dp) :: noise = 0.0_dp            !< relative Gaussian noise on stress (synthetic data)
      integer :: seed = 1                   !< noise seed
      !> K, the test's temperature; 0: the model's (&model temperature)
      real(dp) :: temperature = 0.0_dp
      logical :: has_data = .false.
      type(data_spec) :: data
      character(len=:), allocatable :: weighting  !< threshold, relaxation, none, column
      real(dp) :: sig = 0.0_dp              !< threshold stress for 'threshold' weighting
      type(external_spec) :: ext            !< external backend (when ext%enabled)
      logical :: candidate = .false.        !< a candidate test of `usharp design`
      integer :: line = 0                   !< line of its group in the input file
      character(len=:), allocatable :: target    !< data, peaks or both
      character(len=:), allocatable :: gap_fill  !< cycles or linear (history 'data')
      character(len=:), allocatable :: peak_file !< every cycle's peak stresses (target peaks)
      character(len=:), allocatable :: history_file !< the load history read (history 'file')
      real(dp) :: peak_share = 0.5_dp       !< share of the peaks in the test's objective (both)
      !> Largest time increment of the implicit stress update (integrator 'umat', and the
      !> ANSYS deck's DELTIM), s; 0: &solver dt_max. A creep test's months want larger
      !> increments than a cycle's seconds
      real(dp) :: dt_max = 0.0_dp
      !> The compared (and written) times, s, when they are not output_times(hist, dt_out):
      !> the recorded pieces of a gap-filled history, the turning points of a peaks target
      real(dp), allocatable :: tout(:)
      !> Per point of tout: 0 a point of data_file, +1 a cycle's maximum, -1 its minimum
      integer, allocatable :: point_kind(:)
      !> Per point of tout: the measured peak stress (data_unit; 0 at data points) and the
      !> number of the simulated cycle (0 at data points)
      real(dp), allocatable :: peak_y(:)
      integer, allocatable :: peak_cycle(:)
      !> Peaks of peak_file not compared: within the history's time at no turning point of
      !> it, and beyond its time (a whole test's peaks, some of its cycles simulated)
      integer :: peaks_left = 0, peaks_beyond = 0
      !> History 'data': the data file's time, stress (and weight) columns, read with the
      !> history and merged at repeated times (rows), so that the compared data are not read
      !> a second time; data_merged: the rows merged. Unallocated: the data are read when
      !> compared
      real(dp), allocatable :: data_read(:, :)
      integer :: data_merged = 0
   contains
      procedure :: times => test_times
      procedure :: has_peaks => test_has_peaks
   end type test_config

   !> The variables of one &test group as given
   type :: test_values
      character(len=value_len) :: name, history, file, control, data_file, time_column, &
                                  stress_column, strain_column, weight_column, data_unit, &
                                  filter_column, data_format, weighting, backend, output_file, &
                                  output_format, output_time, output_stress, output_unit, &
                                  constants_file, constants_format, command, target, &
                                  gap_fill, peak_file, tmf_phase
      character(len=filter_len + 1) :: filter(max_list), peak_columns(4)
      real(dp) :: dt_out, amp_first, amp_last, quarter_time, levels(max_list), ramp_time, &
                  holds(max_list), up, down, seg_time, strain_range, mean_strain, strain_rate, &
                  period, hold_max, hold_min, final_strain, stress, duration, noise, sig, &
                  time_limit, rates(max_list), peak_share, temperature, tmf_temperatures(2), gap_time, dt_max
      logical :: candidate
      integer :: npeaks, repeats, cycles, seed
   end type test_values

contains

   !> Read every &test group of file (at least one) into tests, in file order; units: the
   !> model's stress unit (the default of data_unit and output_unit)
   subroutine read_test_groups(file, units, tests, error)
      type(nml_file), intent(in) :: file
      character(len=*), intent(in) :: units
      type(test_config), allocatable, intent(out) :: tests(:)
      type(error_type), allocatable, intent(out) :: error
      type(test_values) :: v
      integer :: k, n, ios
      character(len=512) :: msg
      character(len=:), allocatable :: lines(:)
      character(len=:), allocatable :: where
      ! Counted first, allocated once: reading stays linear in the number of tests
      n = count(file%groups%name == 'test')
      if (n == 0) then
         call fatal_error(error, file%path//': no &test group: at least one test is needed')
         return
      end if
      allocate (tests(n))
      n = 0
      do k = 1, size(file%groups)
         if (file%groups(k)%name /= 'test') cycle
         n = n + 1
         call group_text(file, k, lines)
         call test_namelist(v, ios, msg, text=lines)
         where = file%path//': &test #'//str(n)
         if (len_trim(v%name) > 0) where = where//" '"//trim(v%name(:min(len_trim(v%name), 64)))//"'"
         if (ios /= 0) then
            call read_error(error, file, k, where(len(file%path) + 4:), ios, msg, reread)
            return
         end if
         call build_test(v, file%base_dir, units, tests(n), error)
         if (allocated(error)) then
            call prefix_error(error, where//': ')
            return
         end if
         tests(n)%line = file%groups(k)%line
      end do
      call check_unique_names(file%path, tests, error)
   contains
      subroutine reread(lines, ios, msg)
         character(len=*), intent(in) :: lines(:)
         integer, intent(out) :: ios
         character(len=*), intent(out) :: msg
         type(test_values) :: scratch
         call test_namelist(scratch, ios, msg, text=lines)
      end subroutine reread
   end subroutine read_test_groups

   !> Each test writes files named after it: two tests of one name are an error naming both
   subroutine check_unique_names(path, tests, error)
      character(len=*), intent(in) :: path
      type(test_config), intent(in) :: tests(:)
      type(error_type), allocatable, intent(out) :: error
      integer, allocatable :: order(:)
      integer :: i, a, b
      order = name_order(tests)
      do i = 2, size(order)
         if (tests(order(i))%name /= tests(order(i - 1))%name) cycle
         a = min(order(i - 1), order(i))
         b = max(order(i - 1), order(i))
         call fatal_error(error, path//':'//str(tests(b)%line)//": &test #"//str(b)//" '"// &
            tests(b)%name//"': name: &test #"//str(a)//' (line '//str(tests(a)%line)// &
            ') has this name; each test needs its own (its output files are named after it)')
         return
      end do
   end subroutine check_unique_names

   !> The permutation that sorts the tests by name (merge sort: n log n for many tests)
   function name_order(tests) result(order)
      type(test_config), intent(in) :: tests(:)
      integer, allocatable :: order(:)
      integer, allocatable :: tmp(:)
      integer :: n, width, lo, mid, hi, i, j, k
      n = size(tests)
      order = [(i, i=1, n)]
      allocate (tmp(n))
      width = 1
      do while (width < n)
         do lo = 1, n, 2*width
            mid = min(lo + width - 1, n)
            hi = min(lo + 2*width - 1, n)
            i = lo
            j = mid + 1
            do k = lo, hi
               if (j > hi) then
                  tmp(k) = order(i); i = i + 1
               else if (i > mid) then
                  tmp(k) = order(j); j = j + 1
               else if (llt(tests(order(j))%name, tests(order(i))%name)) then
                  tmp(k) = order(j); j = j + 1
               else
                  tmp(k) = order(i); i = i + 1
               end if
            end do
         end do
         order = tmp
         width = 2*width
      end do
   end function name_order

   !> One test from its group's values, checked; its history is built here
   subroutine build_test(v, base_dir, units, t, error)
      type(test_values), intent(inout) :: v
      character(len=*), intent(in) :: base_dir, units
      type(test_config), intent(out) :: t
      type(error_type), allocatable, intent(out) :: error
      integer :: nlev, nhold, i
      call check_lengths(v, error)
      if (allocated(error)) return
      if (len_trim(v%name) == 0) then
         call fatal_error(error, 'name is not set')
         return
      end if
      if (len_trim(v%name) > name_len) then
         call fatal_error(error, "name = '"//v%name(:name_len)//"...': a test name is at most "//str(name_len)// &
            ' characters (it names files and the rows of reports)')
         return
      end if
      if (verify(trim(v%name), 'abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_-.') /= 0) then
         call fatal_error(error, "name = '"//trim(v%name)//"' may hold only letters, digits, _ - .")
         return
      end if
      t%name = trim(v%name)
      t%candidate = v%candidate
      t%history_kind = lower_text(trim(v%history))
      if (.not. (v%dt_out >= 0.0_dp)) then
         call fatal_error(error, 'dt_out must be >= 0 s')
         return
      end if
      t%dt_out = v%dt_out
      if (v%noise < 0.0_dp) then
         call fatal_error(error, 'noise must be >= 0')
         return
      end if
      t%noise = v%noise
      t%seed = v%seed
      if (.not. (v%temperature >= 0.0_dp)) then
         call fatal_error(error, 'temperature = '//str(v%temperature)//' K: must be > 0 '// &
                          '(0: the temperature of &model)')
         return
      end if
      t%temperature = v%temperature
      if (.not. v%sig >= 0.0_dp) then
         call fatal_error(error, 'sig = '//str(v%sig)//': the threshold stress of '// &
                          "weighting = 'threshold' must be >= 0 (the model's stress unit)")
         return
      end if
      t%sig = v%sig
      t%weighting = lower_text(trim(v%weighting))
      select case (t%weighting)
      case ('none', 'threshold', 'relaxation', 'column')
      case default
         call fatal_error(error, "weighting = '"//trim(v%weighting)// &
            "' is not known (none, threshold, relaxation, column)")
         return
      end select
      if (t%weighting == 'column' .and. len_trim(v%weight_column) == 0) then
         call fatal_error(error, "weighting = 'column' needs weight_column")
         return
      end if
      t%target = lower_text(trim(v%target))
      select case (t%target)
      case ('data', 'peaks', 'both')
      case default
         call fatal_error(error, "target = '"//trim(v%target)//"' is not known (data, peaks, both)")
         return
      end select
      t%gap_fill = lower_text(trim(v%gap_fill))
      if (t%gap_fill /= 'cycles' .and. t%gap_fill /= 'linear') then
         call fatal_error(error, "gap_fill = '"//trim(v%gap_fill)//"' is not known (cycles or linear)")
         return
      end if
      t%peak_file = ''
      if (len_trim(v%peak_file) > 0) t%peak_file = resolve_path(base_dir, trim(v%peak_file))
      if (t%target /= 'data' .and. len_trim(v%peak_file) == 0) then
         call fatal_error(error, "target = '"//t%target//"' needs peak_file")
         return
      end if
      if (t%target == 'data' .and. len_trim(v%peak_file) > 0) then
         call fatal_error(error, "peak_file is set but target = 'data' does not compare it "// &
                          "(target = 'peaks' or 'both')")
         return
      end if
      if (t%target == 'both' .and. len_trim(v%data_file) == 0) then
         call fatal_error(error, "target = 'both' needs data_file")
         return
      end if
      if (.not. (v%peak_share > 0.0_dp .and. v%peak_share < 1.0_dp)) then
         call fatal_error(error, 'peak_share must lie between 0 and 1 (exclusive)')
         return
      end if
      t%peak_share = v%peak_share
      if (.not. (v%dt_max >= 0.0_dp)) then
         call fatal_error(error, 'dt_max must be > 0 (s), or 0 for &solver dt_max')
         return
      end if
      t%dt_max = v%dt_max
      t%has_data = len_trim(v%data_file) > 0 .or. t%target /= 'data'
      t%data%file = resolve_path(base_dir, trim(v%data_file))
      t%data%time_col = trim(v%time_column)
      t%data%stress_col = trim(v%stress_column)
      t%data%strain_col = trim(v%strain_column)
      t%data%weight_col = trim(v%weight_column)
      t%data%unit = trim(v%data_unit)
      if (len_trim(v%data_unit) == 0) t%data%unit = units
      if (lower_text(t%data%unit) == 'mpa') t%data%unit = 'MPa'
      if (t%data%unit /= 'ksi' .and. t%data%unit /= 'MPa') then
         call fatal_error(error, "data_unit = '"//trim(v%data_unit)//"' is not known (ksi or MPa)")
         return
      end if
      t%data%filter_col = trim(v%filter_column)
      allocate (t%data%filter_values(count(len_trim(v%filter) > 0)))
      nlev = 0
      do i = 1, max_list
         if (len_trim(v%filter(i)) == 0) cycle
         nlev = nlev + 1
         t%data%filter_values(nlev) = v%filter(i)
      end do
      ! Each needs the other: a filter without its column was ignored, and all rows were read
      if (size(t%data%filter_values) > 0 .and. len(t%data%filter_col) == 0) then
         call fatal_error(error, 'filter needs filter_column (the column whose text it selects)')
         return
      else if (len(t%data%filter_col) > 0 .and. size(t%data%filter_values) == 0) then
         call fatal_error(error, "filter_column = '"//t%data%filter_col//"' needs filter (the "// &
            'texts of the rows to keep)')
         return
      end if
      t%data%format = trim(v%data_format)
      if (len(t%data%format) > 0) then
         if (.not. numbers_format(t%data%format)) then
            call fatal_error(error, "data_format = '"//t%data%format//"' is not a Fortran format "// &
               "of numbers (e.g. '(2E12.5)', in parentheses)")
            return
         end if
      end if
      call build_external(v, t%name, units, t%ext, error)
      if (allocated(error)) return
      nlev = count(v%levels /= unset)
      nhold = count(v%holds /= unset)
      select case (t%history_kind)
      case ('thesis_lcf')
         call thesis_lcf_history(v%amp_first, v%amp_last, v%npeaks, v%quarter_time, t%hist, error)
      case ('relaxation')
         if (nlev == 0) then
            v%levels(1:2) = [0.00075_dp, 0.001_dp]
            nlev = 2
         end if
         if (nhold == 0) then
            v%holds(1:nlev) = 600.0_dp
            nhold = nlev
         end if
         call relaxation_history(v%levels(:nlev), v%ramp_time, v%holds(:nhold), t%hist, error)
      case ('ratchet')
         call ratchet_history(v%up, v%down, v%repeats, v%seg_time, t%hist, error)
      case ('cyclic')
         if (v%strain_range == unset) then
            call fatal_error(error, "history 'cyclic' needs strain_range")
            return
         end if
         if (v%strain_rate > 0.0_dp .and. v%period > 0.0_dp) then
            call fatal_error(error, "history 'cyclic' takes strain_rate or period, not both")
            return
         end if
         call cyclic_history(v%strain_range, v%mean_strain, v%strain_rate, v%period, v%cycles, &
                             v%hold_max, v%hold_min, t%hist, error)
      case ('tensile')
         if (v%final_strain == unset) then
            call fatal_error(error, "history 'tensile' needs final_strain")
            return
         end if
         call tensile_history(v%strain_rate, v%final_strain, t%hist, error)
      case ('rate_jump')
         if (v%final_strain == unset .or. count(v%rates /= unset) == 0) then
            call fatal_error(error, "history 'rate_jump' needs rates and final_strain")
            return
         end if
         call rate_jump_history(pack(v%rates, v%rates /= unset), v%final_strain, t%hist, error)
      case ('creep')
         if (v%stress == unset .or. v%duration == unset) then
            call fatal_error(error, "history 'creep' needs stress and duration")
            return
         end if
         call creep_history(v%stress, v%ramp_time, v%duration, t%hist, error)
      case ('file')
         if (len_trim(v%file) == 0) then
            call fatal_error(error, "history 'file' needs file")
            return
         end if
         t%history_file = resolve_path(base_dir, trim(v%file))
         call file_history(t%history_file, lower_text(trim(v%control)), &
                           trim(v%time_column), trim(v%strain_column), trim(v%stress_column), &
                           t%hist, error)
      case ('data')
         if (len_trim(v%data_file) == 0) then
            call fatal_error(error, "history 'data' needs data_file")
            return
         end if
         if (v%gap_time < 0.0_dp) then
            call fatal_error(error, 'gap_time must be > 0 (s), or 0 for 50 times the median step')
            return
         end if
         ! The cycles that fill the gaps stay within a push-pull cycle's strains, as a
         ! programmed cycling does (0.5 meant as 0.5 % is caught)
         if (v%strain_range /= unset) then
            if (abs(v%mean_strain) + 0.5_dp*abs(v%strain_range) > max_cycle_strain) then
               call fatal_error(error, 'the cycles that fill the gaps (mean_strain +- strain_range/2) '// &
                  'reach a strain of '//real_str(abs(v%mean_strain) + 0.5_dp*abs(v%strain_range), 'g0.4')// &
                  ', beyond the '//real_str(100.0_dp*max_cycle_strain, 'f0.0')//' % no push-pull cycle '// &
                  'reaches: strain is in mm/mm (is strain_range or mean_strain in percent?)')
               return
            end if
         else if (v%mean_strain /= 0.0_dp) then
            call fatal_error(error, 'mean_strain needs strain_range: together they state the '// &
                             'cycles that fill the gaps')
            return
         end if
         call data_history(t%data, t%gap_fill, merge(v%strain_range, 0.0_dp, v%strain_range /= unset), &
                           v%mean_strain, v%strain_rate, v%duration, t%hist, t%dt_out, t%tout, error, &
                           compared_columns(t, .false.), t%data_read, t%data_merged, v%gap_time)
      case ('')
         call fatal_error(error, 'history is not set (thesis_lcf, relaxation, ratchet, '// &
            'cyclic, tensile, rate_jump, creep, file, data)')
      case default
         call fatal_error(error, "history = '"//trim(v%history)//"' is not known (thesis_lcf, "// &
            'relaxation, ratchet, cyclic, tensile, rate_jump, creep, file, data)')
      end select
      if (allocated(error)) return
      ! A strain beyond 1 (100 %) is what a range or end given in percent makes (3 for
      ! 3 %): the test would be simulated a hundred times too large. A push-pull cycle stays
      ! within 10 % (a specimen buckles long before): beyond it, 0.5 meant as 0.5 % is caught
      if (t%hist%control == control_strain .and. t%history_kind /= 'data') then
         if (maxval(abs(t%hist%v)) > max_strain) then
            call fatal_error(error, "history '"//t%history_kind//"' reaches a strain of "// &
               real_str(maxval(abs(t%hist%v)), 'g0.4')//': strain is in mm/mm (is '// &
               strain_source(t%history_kind)//' in percent?)')
            return
         end if
         if (any(t%history_kind == ['cyclic    ', 'thesis_lcf']) .and. &
             maxval(abs(t%hist%v)) > max_cycle_strain) then
            call fatal_error(error, "history '"//t%history_kind//"' reaches a strain of "// &
               real_str(maxval(abs(t%hist%v)), 'g0.4')//', beyond the '// &
               real_str(100.0_dp*max_cycle_strain, 'f0.0')//' % no push-pull cycle reaches: '// &
               'strain is in mm/mm (is '//strain_source(t%history_kind)//' in percent?)')
            return
         end if
      end if
      ! Output times beyond what a simulation can hold overflow their count (a crash, not a
      ! message): dt_out = 1e-9 s over a 240 s test
      if (t%dt_out > 0.0_dp) then
         if ((t%hist%end_time() - t%hist%t(1))/t%dt_out > real(max_points, dp)) then
            call fatal_error(error, 'dt_out = '//real_str(t%dt_out, 'es10.3')//' s gives '// &
               real_str(aint((t%hist%end_time() - t%hist%t(1))/t%dt_out) + 1.0_dp, 'f0.0')// &
               ' output times over the '// &
               real_str(t%hist%end_time() - t%hist%t(1), 'es10.3')//' s of the test; at most '// &
               str(max_points))
            return
         end if
      end if
      if (any(v%tmf_temperatures /= 0.0_dp)) call add_tmf(v, t, error)
      if (allocated(error) .or. t%target == 'data') return
      if (t%hist%control /= control_strain .or. t%ext%enabled) then
         call fatal_error(error, "target = '"//t%target//"' needs a strain-controlled history "// &
                          'simulated by the internal integrator (the peaks are stresses)')
         return
      end if
      call add_peak_points(t, v%peak_columns, error)
   end subroutine build_test

   !> A thermomechanical test: the temperature follows the command between the two of
   !> tmf_temperatures (K), in or out of phase; the model is set up at the temperature the
   !> test starts at (the initial state's)
   pure subroutine add_tmf(v, t, error)
      type(test_values), intent(in) :: v
      type(test_config), intent(inout) :: t
      type(error_type), allocatable, intent(out) :: error
      logical :: in_phase
      if (.not. all(v%tmf_temperatures > 0.0_dp)) then
         call fatal_error(error, 'tmf_temperatures = '//str(v%tmf_temperatures(1))//', '// &
                          str(v%tmf_temperatures(2))//' K: needs two temperatures > 0 K')
         return
      end if
      if (v%temperature > 0.0_dp) then
         call fatal_error(error, 'temperature and tmf_temperatures are both set: a test '// &
                          'runs at one temperature or under a temperature cycle')
         return
      end if
      if (t%ext%enabled) then
         call fatal_error(error, 'tmf_temperatures needs the internal backend')
         return
      end if
      select case (lower_text(trim(v%tmf_phase)))
      case ('in', 'in-phase'); in_phase = .true.
      case ('out', 'out-of-phase'); in_phase = .false.
      case default
         call fatal_error(error, "tmf_phase = '"//trim(v%tmf_phase)//"' is not known (in, out)")
         return
      end select
      call add_tmf_temperature(t%hist, minval(v%tmf_temperatures), maxval(v%tmf_temperatures), &
                               in_phase, error)
      if (allocated(error)) then
         call prefix_error(error, 'tmf_temperatures: ')
         return
      end if
      t%temperature = t%hist%temp(1)
   end subroutine add_tmf

   !> The measured peak stresses of test t's peak_file (columns: time of the maximum, the
   !> maximum, time of the minimum, the minimum) as compared points at the turning points of
   !> its history (match_peaks), merged with its data points (target 'both') in time order
   subroutine add_peak_points(t, columns, error)
      type(test_config), intent(inout) :: t
      character(len=*), intent(in) :: columns(:)
      type(error_type), allocatable, intent(out) :: error
      real(dp), allocatable :: vals(:, :), tp(:), yp(:), td(:)
      integer, allocatable :: kp(:), corner(:), cyc(:), order(:)
      integer :: n, m, i, k
      logical, allocatable :: inside(:)
      call read_columns(t%peak_file, columns, vals, error, skip_missing=.true.)
      if (allocated(error)) return
      n = size(vals, 1)
      ! A column read in the place of another (a stress for a time, the maximum's time for the
      ! minimum's) would be matched to turning points as it comes: each time column runs
      ! forward, and each row's maximum lies above its minimum
      do k = 1, 3, 2
         i = findloc(vals(2:, k) < vals(:n - 1, k), .true., 1)
         if (i > 0) then
            call fatal_error(error, t%peak_file//": column '"//trim(columns(k))//"' (the time of the "// &
               trim(merge('maximum', 'minimum', k == 1))//', s) goes back from '//real_str(vals(i, k), 'g0.6')// &
               ' to '//real_str(vals(i + 1, k), 'g0.6')//' at row '//str(i + 1)//' of those read: is it a time? '// &
               '(peak_columns: time of the maximum, maximum, time of the minimum, minimum)')
            return
         end if
         ! A cycle's row repeated (an export written twice) has no turning point of its own
         i = findloc(vals(2:, k) == vals(:n - 1, k), .true., 1)
         if (i > 0) then
            call fatal_error(error, t%peak_file//": rows "//str(i)//' and '//str(i + 1)//" of those read "// &
               "repeat the time '"//trim(columns(k))//"' = "//real_str(vals(i, k), 'g0.6')// &
               ' s: one cycle has one maximum and one minimum (a row written twice?)')
            return
         end if
      end do
      i = findloc(vals(:, 2) < vals(:, 4), .true., 1)
      if (i > 0) then
         call fatal_error(error, t%peak_file//": at row "//str(i)//" of those read the maximum ('"// &
            trim(columns(2))//"', "//real_str(vals(i, 2), 'g0.6')//") lies below the minimum ('"// &
            trim(columns(4))//"', "//real_str(vals(i, 4), 'g0.6')//'): are the columns in the order '// &
            'of peak_columns (time of the maximum, maximum, time of the minimum, minimum)?')
         return
      end if
      tp = [vals(:, 1), vals(:, 3)]
      yp = [vals(:, 2), vals(:, 4)]
      kp = [spread(1, 1, n), spread(-1, 1, n)]
      call match_peaks(t%hist, tp, kp, corner, cyc)
      if (count(corner > 0) == 0) then
         call fatal_error(error, t%peak_file//': no peak lies at a turning point of the '// &
                          "history (target = '"//t%target//"')")
         return
      end if
      inside = tp >= t%hist%t(1) .and. tp <= t%hist%end_time()
      t%peaks_beyond = count(corner == 0 .and. .not. inside)
      t%peaks_left = count(corner == 0 .and. inside)
      ! Peaks of one kind within the history's time of which none is at a turning point of
      ! that kind are not the test's (the minimum's time in the place of the maximum's)
      do k = -1, 1, 2
         if (any(inside .and. kp == k) .and. .not. any(corner > 0 .and. kp == k)) then
            call fatal_error(error, t%peak_file//': none of its '//str(count(inside .and. kp == k))//' '// &
               trim(merge('maxima', 'minima', k == 1))//' within the simulated time lies at a '// &
               trim(merge('maximum', 'minimum', k == 1))//" of the history: is column '"// &
               trim(columns(2 - k))//"' the time of the "//trim(merge('maximum', 'minimum', k == 1))//'?')
            return
         end if
      end do
      tp = t%hist%t(pack(corner, corner > 0))
      yp = pack(yp, corner > 0)
      kp = pack(kp, corner > 0)
      cyc = pack(cyc, corner > 0)
      order = order_of(tp)
      if (t%target == 'both') then
         td = t%times()
      else
         allocate (td(0))
      end if
      m = size(td)
      t%tout = [td, tp(order)]
      t%point_kind = [spread(0, 1, m), kp(order)]
      t%peak_y = [spread(0.0_dp, 1, m), yp(order)]
      t%peak_cycle = [spread(0, 1, m), cyc(order)]
      order = order_of(t%tout)
      t%tout = t%tout(order)
      t%point_kind = t%point_kind(order)
      t%peak_y = t%peak_y(order)
      t%peak_cycle = t%peak_cycle(order)
   end subroutine add_peak_points

   !> The times (s) at which test self is simulated, compared and written
   pure function test_times(self) result(times)
      class(test_config), intent(in) :: self
      real(dp), allocatable :: times(:)
      if (allocated(self%tout)) then
         times = self%tout
      else
         times = output_times(self%hist, self%dt_out)
      end if
   end function test_times

   !> Whether some compared points of test self are peak stresses of its cycles
   pure logical function test_has_peaks(self)
      class(test_config), intent(in) :: self
      test_has_peaks = .false.
      if (allocated(self%point_kind)) test_has_peaks = any(self%point_kind /= 0)
   end function test_has_peaks

   !> No character value may have been cut at its buffer's length
   subroutine check_lengths(v, error)
      type(test_values), intent(in) :: v
      type(error_type), allocatable, intent(out) :: error
      integer :: i
      call check_length(error, '', 'name', v%name)
      call check_length(error, '', 'history', v%history)
      call check_length(error, '', 'file', v%file)
      call check_length(error, '', 'control', v%control)
      call check_length(error, '', 'data_file', v%data_file)
      call check_length(error, '', 'time_column', v%time_column)
      call check_length(error, '', 'stress_column', v%stress_column)
      call check_length(error, '', 'strain_column', v%strain_column)
      call check_length(error, '', 'weight_column', v%weight_column)
      call check_length(error, '', 'data_unit', v%data_unit)
      call check_length(error, '', 'filter_column', v%filter_column)
      call check_length(error, '', 'data_format', v%data_format)
      call check_length(error, '', 'weighting', v%weighting)
      call check_length(error, '', 'backend', v%backend)
      call check_length(error, '', 'command', v%command)
      call check_length(error, '', 'output_file', v%output_file)
      call check_length(error, '', 'output_format', v%output_format)
      call check_length(error, '', 'output_time', v%output_time)
      call check_length(error, '', 'output_stress', v%output_stress)
      call check_length(error, '', 'output_unit', v%output_unit)
      call check_length(error, '', 'constants_file', v%constants_file)
      call check_length(error, '', 'constants_format', v%constants_format)
      call check_length(error, '', 'target', v%target)
      call check_length(error, '', 'gap_fill', v%gap_fill)
      call check_length(error, '', 'peak_file', v%peak_file)
      do i = 1, max_list
         call check_length(error, '', 'filter', v%filter(i))
      end do
      do i = 1, size(v%peak_columns)
         call check_length(error, '', 'peak_columns', v%peak_columns(i))
      end do
   end subroutine check_lengths

   !> The external backend's settings, checked
   subroutine build_external(v, test_name, units, ext, error)
      type(test_values), intent(in) :: v
      character(len=*), intent(in) :: test_name, units
      type(external_spec), intent(out) :: ext
      type(error_type), allocatable, intent(out) :: error
      character(len=64) :: probe
      integer :: ios
      select case (lower_text(trim(v%backend)))
      case ('internal')
         ext%enabled = .false.
      case ('external')
         ext%enabled = .true.
      case default
         call fatal_error(error, "backend = '"//trim(v%backend)//"' is not known (internal or external)")
         return
      end select
      ext%command = trim(v%command)
      ext%output_file = trim(v%output_file)
      if (len_trim(v%output_file) == 0) ext%output_file = test_name//'_prvar.txt'
      ext%output_format = lower_text(trim(v%output_format))
      ext%time_title = trim(v%output_time)
      ext%stress_title = trim(v%output_stress)
      ext%unit = trim(v%output_unit)
      if (len_trim(v%output_unit) == 0) ext%unit = units
      if (lower_text(ext%unit) == 'mpa') ext%unit = 'MPa'
      ext%constants_file = trim(v%constants_file)
      ext%constants_format = trim(v%constants_format)
      ext%time_limit = v%time_limit
      if (.not. ext%enabled) return
      if (len_trim(v%command) == 0) then
         call fatal_error(error, "backend = 'external' needs command")
      else if (ext%output_format /= 'prvar' .and. ext%output_format /= 'columns') then
         call fatal_error(error, "output_format = '"//trim(v%output_format)// &
            "' is not known (prvar or columns)")
      else if (ext%unit /= 'ksi' .and. ext%unit /= 'MPa') then
         call fatal_error(error, "output_unit = '"//trim(v%output_unit)//"' is not known (ksi or MPa)")
      else if (.not. (v%time_limit > 0.0_dp)) then
         call fatal_error(error, 'time_limit must be > 0 s')
      else if (len_trim(v%constants_file) == 0 .or. index(v%constants_file, '/') > 0) then
         call fatal_error(error, "constants_file = '"//trim(v%constants_file)// &
            "' must be a plain file name (it is written into the work folder)")
      else if (index(ext%output_file, '/') > 0 .or. index(ext%output_file, '..') > 0) then
         call fatal_error(error, "output_file = '"//ext%output_file// &
            "' must be a plain file name inside the work folder")
      end if
      if (allocated(error)) return
      write (probe, ext%constants_format, iostat=ios) 1.0_dp
      if (ios /= 0 .or. verify(ext%constants_format, '()0123456789.EeSsDdGg') /= 0) then
         call fatal_error(error, "constants_format = '"//ext%constants_format// &
            "' is not a Fortran format for one real such as (E12.5)")
      end if
   end subroutine build_external

   !> Write &test with its defaults to unit (reals without a default: -huge)
   subroutine write_test_defaults(unit)
      integer, intent(in) :: unit
      type(test_values) :: v
      integer :: ios
      character(len=512) :: msg
      call test_namelist(v, ios, msg, unit=unit)
   end subroutine write_test_defaults

   !> The &test namelist with its defaults (those test_config and external_spec hold come
   !> from them): read from text or written to unit
   subroutine test_namelist(v, ios, msg, text, unit)
      type(test_values), intent(out) :: v
      integer, intent(out) :: ios
      character(len=*), intent(out) :: msg
      character(len=*), intent(in), optional :: text(:)
      integer, intent(in), optional :: unit
      type(test_config) :: d
      character(len=value_len) :: name, history, file, control, data_file, time_column, &
                                  stress_column, strain_column, weight_column, data_unit, &
                                  filter_column, data_format, weighting, backend, output_file, &
                                  output_format, output_time, output_stress, output_unit, &
                                  constants_file, constants_format, command, target, &
                                  gap_fill, peak_file, tmf_phase
      character(len=filter_len + 1) :: filter(max_list), peak_columns(4)
      real(dp) :: dt_out, amp_first, amp_last, quarter_time, levels(max_list), ramp_time, &
                  holds(max_list), up, down, seg_time, strain_range, mean_strain, strain_rate, &
                  period, hold_max, hold_min, final_strain, stress, duration, noise, sig, &
                  time_limit, rates(max_list), peak_share, temperature, tmf_temperatures(2), gap_time, dt_max
      logical :: candidate
      integer :: npeaks, repeats, cycles, seed
      namelist /test/ name, history, dt_out, amp_first, amp_last, npeaks, quarter_time, levels, &
         ramp_time, holds, up, down, repeats, seg_time, strain_range, mean_strain, strain_rate, &
         period, cycles, hold_max, hold_min, final_strain, stress, duration, file, control, &
         data_file, time_column, stress_column, strain_column, weight_column, data_unit, &
         filter_column, filter, data_format, weighting, sig, noise, seed, backend, command, &
         output_file, output_format, output_time, output_stress, output_unit, constants_file, &
         constants_format, time_limit, candidate, rates, target, gap_fill, peak_file, &
         peak_columns, peak_share, temperature, tmf_temperatures, tmf_phase, gap_time, dt_max
      name = ''
      history = ''
      file = ''
      control = 'strain'
      data_file = ''
      time_column = 'time'
      stress_column = 'stress'
      strain_column = 'strain'
      weight_column = ''
      data_unit = ''
      filter_column = ''
      filter = ''
      data_format = ''
      weighting = 'none'
      dt_out = d%dt_out
      amp_first = 0.0005_dp; amp_last = 0.005_dp; npeaks = 12; quarter_time = 10.0_dp
      levels = unset; holds = unset; ramp_time = 1.0_dp
      up = 0.0005_dp; down = 0.00025_dp; repeats = 15; seg_time = 40.0_dp
      strain_range = unset; mean_strain = 0.0_dp; strain_rate = 0.0_dp; period = 0.0_dp
      cycles = 1; hold_max = 0.0_dp; hold_min = 0.0_dp
      final_strain = unset; stress = unset; duration = unset
      noise = d%noise; seed = d%seed; sig = d%sig
      backend = 'internal'; command = ''; output_file = ''; output_format = 'prvar'
      output_time = 'TIME'; output_stress = 'STRESS'; output_unit = ''
      constants_file = 'Constants.txt'; constants_format = '(E12.5)'; time_limit = d%ext%time_limit
      candidate = d%candidate; rates = unset; temperature = d%temperature
      tmf_temperatures = 0.0_dp; tmf_phase = 'in'
      target = 'data'; gap_fill = 'cycles'; peak_file = ''; peak_share = d%peak_share; gap_time = 0.0_dp; dt_max = d%dt_max
      peak_columns = [character(len=filter_len + 1) :: 'time_max', 'max', 'time_min', 'min']
      ios = 0
      msg = ''
      if (present(text)) read (text, nml=test, iostat=ios, iomsg=msg)
      if (present(unit)) write (unit, nml=test, iostat=ios, iomsg=msg)
      v%name = name; v%history = history; v%file = file; v%control = control
      v%data_file = data_file; v%time_column = time_column; v%stress_column = stress_column
      v%strain_column = strain_column; v%weight_column = weight_column; v%data_unit = data_unit
      v%filter_column = filter_column; v%data_format = data_format; v%weighting = weighting
      v%backend = backend; v%output_file = output_file; v%output_format = output_format
      v%output_time = output_time; v%output_stress = output_stress; v%output_unit = output_unit
      v%constants_file = constants_file; v%constants_format = constants_format
      v%command = command; v%filter = filter
      v%dt_out = dt_out; v%amp_first = amp_first; v%amp_last = amp_last
      v%quarter_time = quarter_time; v%levels = levels; v%ramp_time = ramp_time
      v%holds = holds; v%up = up; v%down = down; v%seg_time = seg_time
      v%strain_range = strain_range; v%mean_strain = mean_strain; v%strain_rate = strain_rate
      v%period = period; v%hold_max = hold_max; v%hold_min = hold_min
      v%final_strain = final_strain; v%stress = stress; v%duration = duration
      v%noise = noise; v%sig = sig; v%time_limit = time_limit; v%rates = rates
      v%candidate = candidate; v%npeaks = npeaks; v%repeats = repeats; v%cycles = cycles
      v%seed = seed; v%target = target; v%gap_fill = gap_fill; v%peak_file = peak_file
      v%peak_columns = peak_columns; v%peak_share = peak_share; v%temperature = temperature
      v%tmf_temperatures = tmf_temperatures; v%tmf_phase = tmf_phase; v%gap_time = gap_time; v%dt_max = dt_max
   end subroutine test_namelist

   !> History from a file of (time, value) points; control is 'strain' or 'stress'
   subroutine file_history(path, control, time_col, strain_col, stress_col, hist, error)
      character(len=*), intent(in) :: path, control
      !> the columns of time and of the commanded strain or stress (names or positions) in a
      !> file with a header row; a file of bare numbers holds time and value in columns 1 and 2
      character(len=*), intent(in) :: time_col, strain_col, stress_col
      type(history_type), intent(out) :: hist
      type(error_type), allocatable, intent(out) :: error
      real(dp), allocatable :: vals(:, :)
      character(len=:), allocatable :: cols(:)
      integer :: mode
      select case (control)
      case ('strain'); mode = control_strain
      case ('stress'); mode = control_stress
      case default
         call fatal_error(error, "control = '"//control//"' is not known (strain or stress)")
         return
      end select
      allocate (character(len=max(len(time_col), len(strain_col), len(stress_col))) :: cols(2))
      cols(1) = time_col
      if (mode == control_strain) then
         cols(2) = strain_col
      else
         cols(2) = stress_col
      end if
      call read_columns(path, cols, vals, error, unnamed=['1', '2'], time_first=.true.)
      if (allocated(error)) return
      call history_from_points(vals(:, 1), vals(:, 2), mode, hist, error)
      if (allocated(error)) call prefix_error(error, path//': ')
   end subroutine file_history

   !> The columns of a test's data file compared with its simulation, besides time: the
   !> response (the strain where it is fitted, else the stress) and the weight column of
   !> weighting 'column'; none for a peaks target (its peaks file is the data). The one list
   !> that data_history reads with the history and load_experiment reads otherwise
   pure function compared_columns(t, fits_strain) result(cols)
      type(test_config), intent(in) :: t
      !> the strain is the fitted response (a stress-controlled test)
      logical, intent(in) :: fits_strain
      character(len=:), allocatable :: cols(:)
      integer :: n
      n = merge(0, merge(2, 1, t%weighting == 'column'), t%target == 'peaks')
      allocate (character(len=max(len(t%data%stress_col), len(t%data%strain_col), &
                                  len(t%data%weight_col))) :: cols(n))
      if (n == 0) return
      if (fits_strain) then
         cols(1) = t%data%strain_col
      else
         cols(1) = t%data%stress_col
      end if
      if (n == 2) cols(2) = t%data%weight_col
   end function compared_columns

   !> Strain-controlled history from a measured file's time and strain columns. With
   !> gap_fill = 'cycles' its gaps (unrecorded cycles between recorded ones) are cycled
   !> through (gap_filled_history; range, mean, rate: the cycles' strain range, mean strain
   !> and rate per s if stated, else 0); with 'linear' each gap is a straight line. When there
   !> are gaps, tout holds the output times (step dt_out, s) inside the recorded pieces only:
   !> what fills a gap is not compared.
   !> With compared (column names), table returns the file's time and those columns as
   !> read with the history, merged at repeated times (nmerged rows), for the comparison;
   !> where they cannot be read with it (a column the file lacks) table is left unallocated
   !> and the comparison reads them and reports why
   subroutine data_history(spec, gap_fill, range, mean, rate, duration, hist, dt_out, tout, error, &
                           compared, table, nmerged, gap_time)
      type(data_spec), intent(in) :: spec
      character(len=*), intent(in) :: gap_fill
      !> the history ends at the last sample at or before duration (s; unset: at the last)
      real(dp), intent(in) :: duration
      real(dp), intent(in) :: range, mean, rate, dt_out
      type(history_type), intent(out) :: hist
      real(dp), allocatable, intent(inout) :: tout(:)
      type(error_type), allocatable, intent(out) :: error
      character(len=*), intent(in) :: compared(:)
      real(dp), allocatable, intent(out) :: table(:, :)
      integer, intent(out) :: nmerged
      !> a time step longer than this is a gap (s; 0: gap_factor times the median step)
      real(dp), intent(in) :: gap_time
      real(dp), allocatable :: vals(:, :), spans(:, :), times(:)
      real(dp) :: tol
      logical, allocatable :: inside(:)
      integer :: j
      character(len=:), allocatable :: cols(:)
      allocate (character(len=max(len(spec%time_col), len(spec%strain_col), len(compared))) :: &
                cols(2 + size(compared)))
      cols(1) = spec%time_col
      cols(2) = spec%strain_col
      cols(3:) = compared
      call read_data_columns(spec, cols, vals, error)
      if (allocated(error) .and. size(cols) > 2) then
         deallocate (error)
         cols = cols(:2)
         call read_data_columns(spec, cols, vals, error)
      end if
      if (allocated(error)) return
      call merge_repeated_times(vals, spec%file, nmerged, error)
      if (allocated(error)) return
      if (size(cols) > 2) table = vals(:, [1, (j, j=3, size(cols))])
      ! A strain beyond 1 (100 %) is no test this model describes, but it is what a column in
      ! percent gives: the loops would be simulated a hundred times too large
      if (maxval(abs(vals(:, 2))) > max_strain) then
         call fatal_error(error, percent_strain(spec%file, spec%strain_col, maxval(abs(vals(:, 2)))))
         return
      end if
      if (duration /= unset) then
         if (count(vals(:, 1) <= duration) < 2) then
            call fatal_error(error, 'duration: fewer than 2 samples of '//spec%file//' lie within it')
            return
         end if
         vals = vals(:count(vals(:, 1) <= duration), :)
      end if
      ! Each recorded piece is smoothed on its own: one spline over a gap bulges across it
      call gap_filled_history(vals(:, 1), vals(:, 2), control_strain, range, mean, rate, &
                              hist, spans, error, straight=gap_fill == 'linear', gap_time=gap_time)
      if (allocated(error)) then
         call prefix_error(error, spec%file//': ')
         return
      end if
      if (size(spans, 2) == 1) return
      times = output_times(hist, dt_out)
      tol = 1.0e-9_dp*max(1.0_dp, abs(times(size(times))))
      allocate (inside(size(times)))
      inside = .false.
      do j = 1, size(spans, 2)
         inside = inside .or. (times >= spans(1, j) - tol .and. times <= spans(2, j) + tol)
      end do
      tout = pack(times, inside)
   end subroutine data_history

   !> Read columns of a data_spec's file with its filter and format
   subroutine read_data_columns(spec, columns, vals, error)
      type(data_spec), intent(in) :: spec
      character(len=*), intent(in) :: columns(:)
      real(dp), allocatable, intent(out) :: vals(:, :)
      type(error_type), allocatable, intent(out) :: error
      call read_columns(spec%file, columns, vals, error, spec%filter_col, spec%filter_values, &
                        spec%format, time_first=.true.)
   end subroutine read_data_columns


   !> The message for a measured strain column that reaches peak > max_strain (in percent)
   pure function percent_strain(file, column, peak) result(text)
      character(len=*), intent(in) :: file, column
      real(dp), intent(in) :: peak
      character(len=:), allocatable :: text
      text = file//": column '"//column//"' reaches "//real_str(peak, 'g0.4')// &
             ': strain is in mm/mm (is it in percent?)'
   end function percent_strain

   !> The variables that set the strains of a history of this kind
   pure function strain_source(kind) result(names)
      character(len=*), intent(in) :: kind
      character(len=:), allocatable :: names
      select case (kind)
      case ('cyclic')
         names = 'strain_range or mean_strain'
      case ('tensile', 'rate_jump')
         names = 'final_strain'
      case ('thesis_lcf')
         names = 'amp_first or amp_last'
      case ('relaxation')
         names = 'levels'
      case ('ratchet')
         names = 'up or down'
      case default
         names = 'the history file'
      end select
   end function strain_source

   !> The &test variables that set a history of this kind
   pure function history_settings(kind) result(names)
      character(len=*), intent(in) :: kind
      character(len=:), allocatable :: names
      select case (kind)
      case ('cyclic')
         names = 'strain_range (max - min), mean_strain, strain_rate or period, hold_max and hold_min'
      case ('thesis_lcf')
         names = 'amp_first, amp_last, npeaks and quarter_time'
      case ('relaxation')
         names = 'levels, ramp_time and holds'
      case ('ratchet')
         names = 'up, down, repeats and seg_time'
      case ('tensile')
         names = 'strain_rate and final_strain'
      case ('rate_jump')
         names = 'rates and final_strain'
      case ('creep')
         names = 'stress and ramp_time'
      case default
         names = 'the history''s settings'
      end select
   end function history_settings
   !> The time increments of the implicit stress update for test (integrator 'umat', the
   !> ANSYS deck): solver's, with the test's own dt_max where it gives one (dt_init then at
   !> most that)
   pure function test_increments(test, solver) result(opts)
      type(test_config), intent(in) :: test
      type(solver_options), intent(in) :: solver
      type(solver_options) :: opts
      opts = solver
      if (test%dt_max > 0.0_dp) then
         opts%dt_max = test%dt_max
         opts%dt_init = min(opts%dt_init, test%dt_max)
         opts%dt_min = min(opts%dt_min, opts%dt_init)
      end if
   end function test_increments
   !> Whether a peak stress is one a test of a metal reaches, against Young's modulus youngs
   !> (the same unit): 0 between min_stress_share and max_stress_share of it, -1 below (a
   !> stress in GPa, a strain), 1 above (a stress in Pa or kPa)
   elemental integer function stress_share_side(peak, youngs) result(side)
      real(dp), intent(in) :: peak, youngs
      ! (the bounds themselves pass, whatever the rounding of their product: 1.44 MPa at
      ! E = 144000 MPa had been refused as below 1e-5 E)
      side = 0
      if (peak < (1.0_dp - bound_slack)*min_stress_share*youngs) then
         side = -1
      else if (peak > (1.0_dp + bound_slack)*max_stress_share*youngs) then
         side = 1
      end if
   end function stress_share_side

end module usharp_input_test
