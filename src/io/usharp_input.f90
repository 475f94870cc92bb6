!> Reading a usharp input file: the file is split into its namelist groups in one pass
!> (usharp_namelist), then each group is read and checked by its own module (&model and
!> &constants: usharp_input_model, &solver, &output, &fit, &design, &diagnose, &test:
!> usharp_input_<group>). Every error names the file and the group and variable, or the line.
module usharp_input
   use usharp_kinds, only: dp
   use usharp_error, only: error_type, prefix_error, fatal_error, stat_usage, stat_input
   use usharp_strings, only: str, lower, real_str
   use usharp_filesys, only: absolute_path, join_path, file_exists
   use usharp_model, only: model_type, model_at
   use usharp_history, only: control_stress
   use usharp_config, only: run_config
   use usharp_namelist, only: nml_file, scan_namelist_file, resolve_path, string_value
   use usharp_input_model, only: read_model_group, read_constants_group
   use usharp_input_solver, only: read_solver_group
   use usharp_input_output, only: read_output_group
   use usharp_input_fit, only: read_fit_group
   use usharp_input_design, only: read_design_group
   use usharp_input_diagnose, only: read_diagnose_group, specimen_unused
   use usharp_input_test, only: read_test_groups, read_data_columns, stress_share_side
   implicit none
   private

   public :: read_config, read_config_as, override_constants, resolve_path, known_groups
   public :: check_inputs_kept, check_not_a_fit, output_names
   public :: read_data_columns, specimen_unused

   !> The groups of an input file; all but &test at most once
   character(len=9), parameter :: known_groups(8) = &
      ['model    ', 'constants', 'solver   ', 'output   ', 'fit      ', 'test     ', 'design   ', 'diagnose ']
   character(len=4), parameter :: repeatable(1) = ['test']

contains

   !> Read and check the input file; histories are built, data files are not yet read
   subroutine read_config(path, cfg, error)
      character(len=*), intent(in) :: path
      type(run_config), intent(out) :: cfg
      type(error_type), allocatable, intent(out) :: error
      type(nml_file) :: file
      call scan_namelist_file(path, known_groups, repeatable, file, error)
      if (allocated(error)) return
      cfg%path = path
      cfg%base_dir = file%base_dir
      call read_model_group(file, cfg%model, cfg%units, error)
      if (.not. allocated(error)) call read_constants_group(file, cfg%model, error)
      if (.not. allocated(error)) call read_solver_group(file, cfg%solver, error)
      if (.not. allocated(error)) call read_output_group(file, cfg%out_dir, error)
      if (.not. allocated(error)) call read_fit_group(file, cfg%units, cfg%model, cfg%fit, error)
      if (.not. allocated(error)) call read_design_group(file, cfg%design, error)
      if (.not. allocated(error)) call read_test_groups(file, cfg%units, cfg%tests, error)
      if (.not. allocated(error)) call read_diagnose_group(file, cfg%tests, cfg%diagnose, error)
      if (allocated(error)) return
      call cfg%model%setup(error)
      if (allocated(error)) then
         call setup_error(error, path)
         return
      end if
      call check_test_temperatures(path, cfg, error)
      if (.not. allocated(error)) call check_commanded_stress(path, cfg, error)
   end subroutine read_config

   !> A stress-controlled history's largest stress against Young's modulus, as a data file's
   !> stress is checked: below 1e-5 E a stress in GPa (0.019 for 19 MPa) or a strain, above
   !> 0.05 E one in Pa or kPa
   subroutine check_commanded_stress(path, cfg, error)
      character(len=*), intent(in) :: path
      type(run_config), intent(in) :: cfg
      type(error_type), allocatable, intent(out) :: error
      real(dp) :: peak, e
      integer :: i
      character(len=:), allocatable :: what
      e = cfg%model%youngs
      do i = 1, size(cfg%tests)
         if (cfg%tests(i)%hist%control /= control_stress .or. cfg%tests(i)%history_kind == 'data') cycle
         if (size(cfg%tests(i)%hist%v) == 0) cycle
         peak = maxval(abs(cfg%tests(i)%hist%v))
         if (stress_share_side(peak, e) == 0) cycle
         if (.not. peak > 0.0_dp) then
            call fatal_error(error, path//": &test #"//str(i)//" '"//cfg%tests(i)%name//"': its stress is 0 "// &
               'throughout: a stress-controlled test needs a stress (stress, or the history file)', stat_input)
            return
         end if
         what = 'its stress'
         if (allocated(cfg%tests(i)%history_file)) what = "file = '"//cfg%tests(i)%history_file//"': its stress"
         call fatal_error(error, path//": &test #"//str(i)//" '"//cfg%tests(i)%name//"': "//what//" reaches "// &
            real_str(peak, 'es9.2')//' '//cfg%units//', '//real_str(peak/e, 'es8.1')//" of Young's modulus ("// &
            str(nint(e))//' '//cfg%units//'): no test of a metal loads it so (is the stress in '// &
            trim(merge('GPa or a strain', 'Pa or kPa      ', stress_share_side(peak, e) < 0))//', not '//cfg%units//'?)', &
            stat_input)
         return
      end do
   end subroutine check_commanded_stress

   !> A test at a temperature of its own (or under a temperature cycle, which needs RODAS4):
   !> within the model's range (as &model's), and the
   !> model set up there
   subroutine check_test_temperatures(path, cfg, error)
      character(len=*), intent(in) :: path
      type(run_config), intent(in) :: cfg
      type(error_type), allocatable, intent(out) :: error
      class(model_type), allocatable :: mt
      real(dp), allocatable :: temps(:)
      character(len=:), allocatable :: what
      integer :: i, j
      do i = 1, size(cfg%tests)
         ! A temperature cycle is checked at its two ends
         if (allocated(cfg%tests(i)%hist%temp) .and. cfg%solver%integrator /= 'rodas4') then
            call fatal_error(error, path//": &solver: integrator = '"//trim(cfg%solver%integrator)// &
               "': &test #"//str(i)//" '"//cfg%tests(i)%name//"' has a temperature cycle (tmf_temperatures), "// &
               "which needs 'rodas4'")
            return
         end if
         if (allocated(cfg%tests(i)%hist%temp)) then
            temps = [minval(cfg%tests(i)%hist%temp), maxval(cfg%tests(i)%hist%temp)]
            what = 'tmf_temperatures reaches '
         else
            temps = [cfg%tests(i)%temperature]
            what = 'temperature = '
         end if
         do j = 1, size(temps)
            associate (temp => temps(j))
               if (.not. temp > 0.0_dp) cycle
               if (temp < 0.1_dp*cfg%model%tm .or. temp >= cfg%model%tm) then
                  call fatal_error(error, path//": &test #"//str(i)//" '"//cfg%tests(i)%name//"': "//what// &
                     str(temp)//' K, which must lie between a tenth of tm and tm = '//str(cfg%model%tm)// &
                     ' K (temperatures are in kelvin)')
                  return
               end if
               ! A model whose rates do not follow the temperature would simulate the test at
               ! the model's own, while its output said otherwise
               if (temp /= cfg%model%temperature .and. .not. cfg%model%temperature_matters()) then
                  call fatal_error(error, path//": &test #"//str(i)//" '"//cfg%tests(i)%name//"': "//what// &
                     str(temp)//' K changes nothing: the rates of the '//cfg%model%name()// &
                     ' model here do not depend on the temperature (set &model activation)')
                  return
               end if
               call model_at(cfg%model, temp, mt, error)
               if (allocated(error)) then
                  call prefix_error(error, path//": &test #"//str(i)//" '"//cfg%tests(i)%name//"': at "// &
                                    str(temp)//' K: ')
                  return
               end if
            end associate
         end do
      end do
   end subroutine check_test_temperatures

   !> read_config, then the command line's choices: the constants of another file (a
   !> best.nml; '' for none) and another output folder ('' for &output's)
   subroutine read_config_as(path, constants_file, out_dir, cfg, error)
      character(len=*), intent(in) :: path, constants_file, out_dir
      type(run_config), intent(out) :: cfg
      type(error_type), allocatable, intent(out) :: error
      call read_config(path, cfg, error)
      if (allocated(error)) return
      if (len_trim(constants_file) > 0) then
         call override_constants(cfg, constants_file, error)
         if (allocated(error)) return
      end if
      if (len_trim(out_dir) > 0) cfg%out_dir = trim(out_dir)
   end subroutine read_config_as

   !> No input of a command is a file it writes: an output folder that holds the deck, the
   !> constants given with -c or a test's data, peaks or load history under a name the command
   !> writes there (a test 'lcf' with its data in lcf.sim.txt) would have them overwritten,
   !> even with --force
   subroutine check_inputs_kept(cfg, path, constants_file, fixed, per_test, error, only)
      type(run_config), intent(in) :: cfg
      !> the deck and the constants file given with -c ('' for none)
      character(len=*), intent(in) :: path, constants_file
      !> the names of the files the command writes in cfg%out_dir, and the endings of those
      !> it writes for each test (after the test's name)
      character(len=*), intent(in) :: fixed(:), per_test(:)
      type(error_type), allocatable, intent(out) :: error
      !> the one test the command writes files of (blank or absent: every test)
      character(len=*), intent(in), optional :: only
      character(len=:), allocatable :: inputs(:), outputs(:), here
      integer :: i, j, n
      if (len_trim(cfg%out_dir) == 0) return
      if (len(absolute_path(cfg%out_dir)) == 0) return
      n = max(len(path), len(constants_file), 1)
      do i = 1, size(cfg%tests)
         if (allocated(cfg%tests(i)%data%file)) n = max(n, len(cfg%tests(i)%data%file))
         if (allocated(cfg%tests(i)%peak_file)) n = max(n, len(cfg%tests(i)%peak_file))
         if (allocated(cfg%tests(i)%history_file)) n = max(n, len(cfg%tests(i)%history_file))
      end do
      allocate (character(len=n) :: inputs(0))
      inputs = [character(len=n) :: path, constants_file]
      do i = 1, size(cfg%tests)
         if (allocated(cfg%tests(i)%data%file)) inputs = [character(len=n) :: inputs, cfg%tests(i)%data%file]
         if (allocated(cfg%tests(i)%peak_file)) inputs = [character(len=n) :: inputs, cfg%tests(i)%peak_file]
         if (allocated(cfg%tests(i)%history_file)) &
            inputs = [character(len=n) :: inputs, cfg%tests(i)%history_file]
      end do
      outputs = output_names(cfg, fixed, per_test, only)
      do i = 1, size(inputs)
         if (len_trim(inputs(i)) == 0) cycle
         here = absolute_path(trim(inputs(i)))
         if (len(here) == 0) cycle
         do j = 1, size(outputs)
            if (absolute_path(join_path(cfg%out_dir, trim(outputs(j)))) == here) then
               call fatal_error(error, trim(inputs(i))//': an input of this run, and '// &
                  join_path(cfg%out_dir, trim(outputs(j)))//' is a file it writes; give '// &
                  'another output folder (-o or &output out_dir)')
               return
            end if
         end do
      end do
   end subroutine check_inputs_kept

   !> A command other than run does not write into an output folder that holds a fit (its
   !> fit.journal): the files it writes are the fit's too (a <test>.sim.txt, identify.txt,
   !> summary.txt), there already or written by a fit still running at its end; a usage error
   subroutine check_not_a_fit(cfg, command, fixed, per_test, error)
      type(run_config), intent(in) :: cfg
      !> the command's name, for the message
      character(len=*), intent(in) :: command
      !> the files the command writes, as for check_inputs_kept
      character(len=*), intent(in) :: fixed(:), per_test(:)
      type(error_type), allocatable, intent(out) :: error
      character(len=:), allocatable :: outputs(:)
      integer :: j
      if (len_trim(cfg%out_dir) == 0) return
      if (.not. file_exists(join_path(cfg%out_dir, 'fit.journal'))) return
      outputs = output_names(cfg, fixed, per_test)
      if (size(outputs) == 0) return
      do j = 1, size(outputs)
         if (file_exists(join_path(cfg%out_dir, trim(outputs(j))))) then
            call fatal_error(error, cfg%out_dir//': holds a fit (fit.journal), whose '// &
               trim(outputs(j))//' '//command//' would replace; give '//command// &
               ' another output folder (-o)', stat_usage)
            return
         end if
      end do
      ! None there yet: a fit still running writes them at its end, over this command's
      call fatal_error(error, cfg%out_dir//': holds a fit (fit.journal), which writes '// &
         trim(outputs(1))//' at its end; give '//command//' another output folder (-o)', stat_usage)
   end subroutine check_not_a_fit

   !> The names of the files a command writes in its output folder: fixed, then for each test
   !> of cfg (or only the test named only, when given and not blank) its name followed by each
   !> of per_test ('.sim.txt', ...)
   pure function output_names(cfg, fixed, per_test, only) result(names)
      type(run_config), intent(in) :: cfg
      character(len=*), intent(in) :: fixed(:), per_test(:)
      character(len=*), intent(in), optional :: only
      character(len=:), allocatable :: names(:)
      logical :: chosen(size(cfg%tests))
      integer :: i, j, k, n
      chosen = .true.
      if (present(only)) then
         if (len_trim(only) > 0) chosen = [(cfg%tests(i)%name == only, i=1, size(cfg%tests))]
      end if
      n = len(fixed)
      do i = 1, size(cfg%tests)
         n = max(n, len(cfg%tests(i)%name) + len(per_test))
      end do
      allocate (character(len=n) :: names(size(fixed) + size(per_test)*count(chosen)))
      names(:size(fixed)) = fixed
      k = size(fixed)
      do i = 1, size(cfg%tests)
         if (.not. chosen(i)) cycle
         do j = 1, size(per_test)
            k = k + 1
            names(k) = cfg%tests(i)%name//trim(per_test(j))
         end do
      end do
   end function output_names

   !> Replace the constants of cfg by the &constants group of another file (a best.nml)
   subroutine override_constants(cfg, path, error)
      type(run_config), intent(inout) :: cfg
      character(len=*), intent(in) :: path
      type(error_type), allocatable, intent(out) :: error
      type(nml_file) :: file
      character(len=:), allocatable :: units, name
      call scan_namelist_file(path, known_groups, repeatable, file, error)
      if (allocated(error)) return
      ! A best.nml says which model and units its constants are in: others are refused
      units = string_value(file, 'model', 'units')
      if (len(units) > 0 .and. lower(units) /= lower(cfg%units)) then
         call fatal_error(error, path//": &model: units = '"//units//"', but the constants "// &
            "are wanted in the deck's '"//cfg%units//"'")
         return
      end if
      name = string_value(file, 'model', 'name')
      if (len(name) > 0 .and. lower(name) /= lower(cfg%model%name())) then
         call fatal_error(error, path//": &model: name = '"//name//"', but the deck's model is '"// &
            cfg%model%name()//"'")
         return
      end if
      call read_constants_group(file, cfg%model, error)
      if (allocated(error)) return
      call cfg%model%setup(error)
      if (allocated(error)) call setup_error(error, path)
   end subroutine override_constants

   !> A model's set-up error as a user error of file path, in the group of the quantity its
   !> message starts with: the models name their &model quantities (Tm, temperature, E,
   !> Poisson's ratio, d0) in words an FE user of their material routines reads too
   pure subroutine setup_error(error, path)
      type(error_type), intent(inout) :: error
      character(len=*), intent(in) :: path
      character(len=*), parameter :: model_words(7) = [character(len=24) :: "Poisson's ratio", &
         'temperature', 'Tm ', "Young's modulus", 'fixed initial drag', 'the Arrhenius factor', &
         'an activation energy']
      integer :: k
      do k = 1, size(model_words)
         if (index(error%message, trim(model_words(k))) == 1) then
            call prefix_error(error, path//': &model: ')
            return
         end if
      end do
      if (index(error%message, 'initial drag stress D0') == 1) then
         call prefix_error(error, path//': &model and &constants: ')
      else
         call prefix_error(error, path//': &constants: ')
      end if
   end subroutine setup_error

end module usharp_input
