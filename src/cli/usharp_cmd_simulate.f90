!> `usharp simulate`: simulate every test of an input file and write <out_dir>/<test>.sim.txt
module usharp_cmd_simulate
   use usharp_kinds, only: dp
   use usharp_error, only: error_type, fatal_error, stat_input
   use usharp_strings, only: str, real_str, shell_word
   use usharp_config, only: run_config
   use usharp_input, only: read_config, override_constants, check_inputs_kept, check_not_a_fit
   use usharp_simulation, only: sim_result
   use usharp_simulate, only: simulate_test, add_response_noise, model_lines
   use usharp_history, only: control_strain, control_stress
   use usharp_output, only: write_sim_file
   use usharp_filesys, only: make_dir, join_path
   use usharp_version, only: usharp_version_string
   use usharp_overwrite, only: check_overwrite, simulate_mark
   implicit none
   private

   public :: simulate_command

contains

   !> Run the simulate command. out_dir overrides the input file's &output out_dir when not
   !> empty. Each written file is reported through the written list. A file of a name it
   !> writes that an earlier simulate did not write (a user's) is refused unless force.
   subroutine simulate_command(path, out_dir, written, error, constants_file, only_test, force)
      character(len=*), intent(in) :: path
      character(len=*), intent(in) :: out_dir
      character(len=*), intent(in), optional :: constants_file  !< a best.nml to use
      character(len=*), intent(in), optional :: only_test       !< simulate only this test
      logical, intent(in), optional :: force  !< write over files it did not write (--force)
      character(len=4096), allocatable, intent(out) :: written(:)
      type(error_type), allocatable, intent(out) :: error
      type(run_config) :: cfg
      type(sim_result) :: res
      character(len=:), allocatable :: dir, command, file
      character(len=512), allocatable :: header(:)
      integer :: i
      logical :: one_test, overwrite
      one_test = .false.
      overwrite = .false.
      if (present(force)) overwrite = force
      allocate (written(0))
      call read_config(path, cfg, error)
      if (allocated(error)) return
      command = 'usharp simulate '//shell_word(path)
      if (present(constants_file)) then
         if (len_trim(constants_file) > 0) then
            call override_constants(cfg, constants_file, error)
            if (allocated(error)) return
            command = command//' --constants '//shell_word(trim(constants_file))
         end if
      end if
      dir = cfg%out_dir
      if (len_trim(out_dir) > 0) then
         dir = trim(out_dir)
         command = command//' --out-dir '//shell_word(trim(out_dir))
      end if
      cfg%out_dir = dir
      if (present(only_test)) then
         if (len(only_test) > 0) then
            if (.not. any([(cfg%tests(i)%name == only_test, i=1, size(cfg%tests))])) then
               call fatal_error(error, path//": no &test named '"//only_test//"'", stat_input)
               return
            end if
            command = command//' --test '//shell_word(only_test)
            one_test = .true.
         end if
      end if
      ! (with -t, only that test's curve is written)
      if (present(constants_file)) then
         call check_inputs_kept(cfg, path, constants_file, [character(len=1) ::], ['.sim.txt'], &
                                error, only_test)
      else
         call check_inputs_kept(cfg, path, '', [character(len=1) ::], ['.sim.txt'], error, only_test)
      end if
      if (allocated(error)) return
      ! Not over a fit's curves (the simulation at the deck's constants is not the fit's)
      if (one_test) then
         call check_not_a_fit(cfg, 'simulate', [only_test//'.sim.txt'], [character(len=1) ::], error)
      else
         call check_not_a_fit(cfg, 'simulate', [character(len=1) ::], ['.sim.txt'], error)
      end if
      if (allocated(error)) return
      ! Every file checked before the first is written
      do i = 1, size(cfg%tests)
         if (one_test) then
            if (cfg%tests(i)%name /= only_test) cycle
         end if
         call check_overwrite(dir, [cfg%tests(i)%name//'.sim.txt'], &
            [simulate_mark//cfg%tests(i)%name//"'"], 'simulate', overwrite, error)
         if (allocated(error)) return
      end do
      call make_dir(dir, error)
      if (allocated(error)) return
      do i = 1, size(cfg%tests)
         if (present(only_test)) then
            if (len(only_test) > 0 .and. cfg%tests(i)%name /= only_test) cycle
         end if
         call simulate_test(cfg%model, cfg%solver, cfg%tests(i), res, error)
         if (allocated(error)) return
         call add_response_noise(res, cfg%tests(i)%hist%control, cfg%tests(i)%noise, cfg%tests(i)%seed)
         allocate (header(0))
         header = [character(len=512) :: &
            'usharp '//usharp_version_string//" simulation of test '"//cfg%tests(i)%name// &
            "' (history "//cfg%tests(i)%history_kind//', '// &
            merge('strain', 'stress', cfg%tests(i)%hist%control == control_strain)//' control)', &
            'regenerate: '//command]
         header = [character(len=512) :: header, model_lines(cfg%model, cfg%units, cfg%tests(i), error)]
         if (allocated(error)) return
         if (cfg%tests(i)%noise > 0.0_dp) header = [character(len=512) :: header, &
            trim(merge('strain', 'stress', cfg%tests(i)%hist%control == control_stress))// &
            ' noise: Gaussian, sd = '//real_str(cfg%tests(i)%noise, 'g0.6')//' x max|'// &
            trim(merge('strain', 'stress', cfg%tests(i)%hist%control == control_stress))// &
            '|, seed '//str(cfg%tests(i)%seed)]
         file = join_path(dir, cfg%tests(i)%name//'.sim.txt')
         call write_sim_file(file, res, header, cfg%units, error)
         deallocate (header)
         if (allocated(error)) return
         written = [character(len=4096) :: written, file]
      end do
   end subroutine simulate_command
end module usharp_cmd_simulate
