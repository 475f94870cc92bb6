!> Bad input gives one clear line naming file, group and variable, and a non-zero exit
module test_input
   use testdrive, only: error_type, unittest_type, new_unittest, check, test_failed, skip_test
   use usharp_kinds, only: dp
   use usharp_error, only: uerror => error_type, stat_input, stat_io, stat_usage
   use usharp_config, only: run_config
   use usharp_input, only: read_config
   use usharp_cmd_simulate, only: simulate_command
   use test_util, only: write_text, usharp_exe, read_text, scratch_dir, check_message
   implicit none
   private
   public :: collect_input, deck_lines

   character(len=*), parameter :: base_model = &
      "&model name='miller', units='ksi', temperature=866.15, tm=1800.0, youngs=22.5e3 /"
   character(len=*), parameter :: base_constants = &
      '&constants a1=0.8, a2=7.42e-5, b=1e15, c2=0.1, h1=280, h2=100, n=5.8, q=91000 /'

contains

   subroutine collect_input(testsuite)
      type(unittest_type), allocatable, intent(out) :: testsuite(:)
      testsuite = [ &
         new_unittest('missing-input-file', test_missing_file), &
         new_unittest('misspelled-variable', test_misspelled), &
         new_unittest('unknown-group-line-and-column', test_unknown_group), &
         new_unittest('unknown-history', test_unknown_history), &
         new_unittest('unknown-jacobian', test_unknown_jacobian), &
         new_unittest('external-backend-settings-checked', test_backend_settings), &
         new_unittest('unterminated-group', test_unterminated), &
         new_unittest('constant-not-positive', test_constant), &
         new_unittest('history-file-time-not-increasing', test_file_time), &
         new_unittest('history-file-empty-or-garbled', test_file_garbled), &
         new_unittest('unwritable-output-folder', test_unwritable), &
         new_unittest('simulate-writes-files', test_simulate_ok), &
         new_unittest('integrator-chosen-in-namelist', test_integrator_choice), &
         new_unittest('history-from-measured-strain-column', test_data_history), &
         new_unittest('thesis-data-reproducible-bit-for-bit', test_data_reproducible), &
         new_unittest('cli-exit-codes-and-one-line-errors', test_cli)]
   end subroutine collect_input

   !> An input file of the model, the constants and the given extra lines
   function deck_lines(extra) result(lines)
      character(len=*), intent(in) :: extra(:)
      character(len=200), allocatable :: lines(:)
      lines = [character(len=200) :: base_model, base_constants, extra]
   end function deck_lines

   subroutine expect_config_error(error, name, extra, text)
      type(error_type), allocatable, intent(out) :: error
      character(len=*), intent(in) :: name, extra(:), text
      type(run_config) :: cfg
      type(uerror), allocatable :: uerr
      call read_config(write_text(name, deck_lines(extra)), cfg, uerr)
      call check_message(error, uerr, text)
   end subroutine expect_config_error

   subroutine test_missing_file(error)
      type(error_type), allocatable, intent(out) :: error
      type(run_config) :: cfg
      type(uerror), allocatable :: uerr
      call read_config('no/such/fit.nml', cfg, uerr)
      call check_message(error, uerr, 'no/such/fit.nml: no such input file')
      if (allocated(error)) return
      call check(error, uerr%stat, stat_input, 'input error category')
   end subroutine test_missing_file

   subroutine test_misspelled(error)
      type(error_type), allocatable, intent(out) :: error
      call expect_config_error(error, 'misspelled.nml', [character(len=80) :: &
         "&test name='lcf', history='thesis_lcf', ampfirst=0.001 /"], &
         "misspelled.nml: &test #1 'lcf': Cannot match namelist object name ampfirst")
   end subroutine test_misspelled

   subroutine test_unknown_group(error)
      type(error_type), allocatable, intent(out) :: error
      call expect_config_error(error, 'group.nml', [character(len=80) :: &
         '&tset name="lcf" /'], 'group.nml:3:1: unknown namelist group &tset')
   end subroutine test_unknown_group

   subroutine test_unterminated(error)
      type(error_type), allocatable, intent(out) :: error
      call expect_config_error(error, 'unterminated.nml', [character(len=80) :: &
         "&test name='a', history='tensile', strain_rate=1e-4, final_strain=0.002 /", &
         "&test name='b', history='tensile', strain_rate=1e-4, final_strain=0.002"], &
         "unterminated.nml: &test #2 is not terminated by '/'")
   end subroutine test_unterminated

   subroutine test_unknown_history(error)
      type(error_type), allocatable, intent(out) :: error
      call expect_config_error(error, 'history.nml', [character(len=80) :: &
         "&test name='x', history='sawtooth' /"], "&test #1 'x': history = 'sawtooth' is not known")
   end subroutine test_unknown_history

   subroutine test_unknown_jacobian(error)
      type(error_type), allocatable, intent(out) :: error
      call expect_config_error(error, 'jacobian.nml', [character(len=80) :: &
         "&fit fitted='B', method='lm', jacobian='exact' /", &
         "&test name='x', history='thesis_lcf' /"], &
         "&fit: jacobian = 'exact' is not known (difference, sensitivity)")
   end subroutine test_unknown_jacobian

   subroutine test_backend_settings(error)
      type(error_type), allocatable, intent(out) :: error
      call expect_config_error(error, 'backend.nml', [character(len=80) :: &
         "&test name='x', history='thesis_lcf', backend='ansys' /"], &
         "&test #1 'x': backend = 'ansys' is not known (internal or external)")
      if (allocated(error)) return
      call expect_config_error(error, 'nocommand.nml', [character(len=80) :: &
         "&test name='x', history='thesis_lcf', backend='external' /"], &
         "&test #1 'x': backend = 'external' needs command")
      if (allocated(error)) return
      call expect_config_error(error, 'outformat.nml', [character(len=90) :: &
         "&test name='x', history='thesis_lcf', backend='external', command='true',", &
         "  output_format='odb' /"], "output_format = 'odb' is not known (prvar or columns)")
      if (allocated(error)) return
      call expect_config_error(error, 'cformat.nml', [character(len=90) :: &
         "&test name='x', history='thesis_lcf', backend='external', command='true',", &
         "  constants_format='(A12)' /"], "constants_format = '(A12)' is not a Fortran format")
      if (allocated(error)) return
      call expect_config_error(error, 'timelimit.nml', [character(len=90) :: &
         "&test name='x', history='thesis_lcf', backend='external', command='true',", &
         "  time_limit=0 /"], 'time_limit must be > 0 s')
   end subroutine test_backend_settings

   subroutine test_constant(error)
      type(error_type), allocatable, intent(out) :: error
      type(run_config) :: cfg
      type(uerror), allocatable :: uerr
      character(len=200), allocatable :: lines(:)
      lines = deck_lines([character(len=80) :: "&test name='lcf', history='thesis_lcf' /"])
      lines(2) = '&constants a1=0.8, a2=7.42e-5, b=1e15, c2=0.1, h1=-280, h2=100, n=5.8, q=91000 /'
      call read_config(write_text('negative.nml', lines), cfg, uerr)
      call check_message(error, uerr, 'negative.nml: &constants: constant H1 must be > 0, got -280')
   end subroutine test_constant

   subroutine test_file_time(error)
      type(error_type), allocatable, intent(out) :: error
      character(len=:), allocatable :: hfile
      hfile = write_text('back.hist', [character(len=20) :: '0 0', '10 0.001', '5 0', '20 0'])
      call expect_config_error(error, 'backtime.nml', [character(len=80) :: &
         "&test name='f', history='file', file='back.hist' /"], &
         'back.hist: history time is not increasing at point 3')
   end subroutine test_file_time

   subroutine test_file_garbled(error)
      type(error_type), allocatable, intent(out) :: error
      character(len=:), allocatable :: hfile
      hfile = write_text('empty.hist', [character(len=20) :: '# nothing here'])
      call expect_config_error(error, 'empty.nml', [character(len=80) :: &
         "&test name='f', history='file', file='empty.hist' /"], &
         'empty.hist: needs at least 3 data rows, found 0')
      if (allocated(error)) return
      hfile = write_text('garbled.hist', [character(len=20) :: '0 0', '10 0.0x01', '20 0'])
      call expect_config_error(error, 'garbled.nml', [character(len=80) :: &
         "&test name='f', history='file', file='garbled.hist' /"], &
         "garbled.hist:2:2: '0.0x01' in column 2 is not a number")
   end subroutine test_file_garbled

   subroutine test_unwritable(error)
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: uerr
      character(len=256), allocatable :: written(:)
      character(len=:), allocatable :: path
      path = write_text('unwritable.nml', deck_lines([character(len=80) :: &
         "&test name='t', history='tensile', strain_rate=1e-4, final_strain=0.002 /"]))
      call simulate_command(path, '/proc/usharp-cannot-write-here', written, uerr)
      call check_message(error, uerr, '/proc/usharp-cannot-write-here: output folder cannot be created or written')
      if (allocated(error)) return
      call check(error, uerr%stat, stat_io, 'output error category')
   end subroutine test_unwritable

   subroutine test_simulate_ok(error)
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: uerr
      character(len=256), allocatable :: written(:)
      character(len=:), allocatable :: path, text
      path = write_text('ok.nml', deck_lines([character(len=120) :: &
         "&test name='pull', history='tensile', strain_rate=1e-4, final_strain=0.002, dt_out=2 /", &
         "&test name='creep', history='creep', stress=15.0, ramp_time=1, duration=100 /"]))
      call simulate_command(path, scratch_dir//'/ok-out', written, uerr)
      if (allocated(uerr)) then
         call test_failed(error, uerr%message)
         return
      end if
      call check(error, size(written), 2, 'two files written')
      if (allocated(error)) return
      text = read_text(scratch_dir//'/ok-out/pull.sim.txt')
      call check(error, index(text, '# time strain stress eps_in back_stress drag_stress') > 0, &
                 'column header present')
   end subroutine test_simulate_ok

   !> history = 'data': the strain column of a measured Alloy 617 file drives the simulation
   subroutine test_data_history(error)
      use testdrive, only: skip_test
      use usharp_simulation, only: sim_result
      use usharp_simulate, only: simulate_test
      type(error_type), allocatable, intent(out) :: error
      type(run_config) :: cfg
      type(uerror), allocatable :: uerr
      type(sim_result) :: res
      character(len=*), parameter :: file = '../shared/realdata/a617-950C/lcf/HTM_A19_Cycles_435.csv'
      logical :: exists
      inquire (file=file, exist=exists)
      if (.not. exists) then
         call skip_test(error, 'measured data not found at '//file//' (shared/ not beside the checkout)')
         return
      end if
      ! The deck lives in build/test-scratch, so the file is three folders up
      call read_config(write_text('datahist.nml', deck_lines([character(len=200) :: &
         "&test name='a617', history='data', dt_out=0.5, data_file='../../"//file//"', ", &
         "time_column='Elapsed Time Sec', strain_column='Strain', filter_column='Cycle Label', ", &
         "filter='Cycle 1' /"])), cfg, uerr)
      if (.not. allocated(uerr)) call simulate_test(cfg%model, cfg%solver, cfg%tests(1), res, uerr)
      if (allocated(uerr)) then
         call test_failed(error, uerr%message)
         return
      end if
      ! The history's corners are the file's (time, strain) rows of cycle 1: ends at its last
      ! row and reaches the largest measured strain of cycle 1 (0.00159; 227 rows, 218 times)
      call check(error, size(cfg%tests(1)%hist%t), 218, 'one corner per distinct time of cycle 1')
      if (allocated(error)) return
      call check(error, maxval(cfg%tests(1)%hist%v), 0.00159_dp, 'largest strain of cycle 1', thr=1e-12_dp)
      if (allocated(error)) return
      call check(error, res%strain(size(res%t)), cfg%tests(1)%hist%v(size(cfg%tests(1)%hist%v)), &
                 'simulated strain follows the measured one to the end', thr=1e-15_dp)
   end subroutine test_data_history

   !> &solver integrator = 'umat' runs the single-element driver; an unknown one is an error
   subroutine test_integrator_choice(error)
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: uerr
      character(len=256), allocatable :: written(:)
      character(len=:), allocatable :: text_u, text_c
      character(len=120), parameter :: pull = &
         "&test name='pull', history='tensile', strain_rate=1e-4, final_strain=0.003, dt_out=30 /"
      call simulate_command(write_text('umat.nml', deck_lines([character(len=120) :: &
         "&solver integrator='umat' /", pull])), scratch_dir//'/umat-out', written, uerr)
      if (.not. allocated(uerr)) call simulate_command(write_text('cvode.nml', deck_lines( &
         [character(len=120) :: pull])), scratch_dir//'/cvode-out', written, uerr)
      if (allocated(uerr)) then
         call test_failed(error, uerr%message)
         return
      end if
      text_u = read_text(scratch_dir//'/umat-out/pull.sim.txt')
      text_c = read_text(scratch_dir//'/cvode-out/pull.sim.txt')
      ! Different integrators, so the files differ (but both have the 11 rows of 0..300 s)
      call check(error, len(text_u) > 0 .and. text_u /= text_c, 'umat output differs from cvode output')
      if (allocated(error)) return
      call expect_config_error(error, 'badint.nml', [character(len=80) :: "&solver integrator='rk4' /", &
         "&test name='t', history='tensile', strain_rate=1e-4, final_strain=0.002 /"], &
         "&solver: integrator = 'rk4' is not known (cvode, rodas4 or umat)")
   end subroutine test_integrator_choice

   !> data/thesis and data/thesis-noise1 come back byte for byte from their decks (the
   !> 'regenerate' line differs only by the --out-dir given here)
   subroutine test_data_reproducible(error)
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: uerr
      character(len=256), allocatable :: written(:)
      character(len=:), allocatable :: fresh, kept
      character(len=*), parameter :: sets(2) = ['thesis       ', 'thesis-noise1']
      character(len=*), parameter :: tests(3) = ['lcf    ', 'relax  ', 'ratchet']
      integer :: i, j
      do i = 1, 2
         call simulate_command('decks/'//trim(merge('thesis-data       ', 'thesis-data-noise1', i == 1))//'.nml', &
                               scratch_dir//'/'//trim(sets(i)), written, uerr)
         if (allocated(uerr)) then
            call test_failed(error, uerr%message)
            return
         end if
         do j = 1, 3
            fresh = without_line2(read_text(scratch_dir//'/'//trim(sets(i))//'/'//trim(tests(j))//'.sim.txt'))
            kept = without_line2(read_text('data/'//trim(sets(i))//'/'//trim(tests(j))//'.sim.txt'))
            call check(error, len(kept) > 1000 .and. fresh == kept, &
                       'data/'//trim(sets(i))//'/'//trim(tests(j))//'.sim.txt differs from its regeneration')
            if (allocated(error)) return
         end do
      end do
   contains
      function without_line2(text) result(rest)
         character(len=*), intent(in) :: text
         character(len=:), allocatable :: rest
         integer :: a, b
         a = index(text, new_line('a'))
         b = index(text(a + 1:), new_line('a')) + a
         rest = text(:a)//text(b + 1:)
      end function without_line2
   end subroutine test_data_reproducible

   !> The program itself: exit codes and one-line errors on stderr
   subroutine test_cli(error)
      type(error_type), allocatable, intent(out) :: error
      character(len=:), allocatable :: exe, errfile
      exe = usharp_exe()
      if (len(exe) == 0) then
         call skip_test(error, 'usharp executable not found beside the test program')
         return
      end if
      errfile = scratch_dir//'/stderr.txt'
      call expect_exit(exe, '', 2)
      if (allocated(error)) return
      call expect_exit(exe, 'frobnicate', 2)
      if (allocated(error)) return
      call expect_exit(exe, '--help', 0)
      if (allocated(error)) return
      call expect_exit(exe, '--version', 0)
      if (allocated(error)) return
      call expect_exit(exe, 'simulate --help', 0)
      if (allocated(error)) return
      call expect_exit(exe, 'simulate --version', 0)
      if (allocated(error)) return
      call expect_exit(exe, 'deck --help', 0)
      if (allocated(error)) return
      call expect_exit(exe, 'deck --version', 0)
      if (allocated(error)) return
      call expect_exit(exe, 'deck', 2)
      if (allocated(error)) return
      call expect_exit(exe, 'deck a b c.nml', 2)
      if (allocated(error)) return
      call expect_exit(exe, 'deck nosuch decks/thesis-data.nml -o '//scratch_dir//'/decks', stat_input)
      if (allocated(error)) return
      call check(error, read_text(errfile) == "usharp: error: decks/thesis-data.nml: no &test named 'nosuch'"// &
                 new_line('a'), 'deck of an unknown test: '//read_text(errfile))
      if (allocated(error)) return
      call expect_exit(exe, 'simulate no-such.nml', stat_input)
      if (allocated(error)) return
      call check(error, read_text(errfile) == 'usharp: error: no-such.nml: no such input file'//new_line('a'), &
                 'one line on stderr, no backtrace: '//read_text(errfile))
   contains
      subroutine expect_exit(exe, args, code)
         character(len=*), intent(in) :: exe, args
         integer, intent(in) :: code
         integer :: stat
         call execute_command_line(exe//' '//args//' > /dev/null 2> '//errfile, exitstat=stat)
         call check(error, stat, code, "exit code of 'usharp "//args//"'")
      end subroutine expect_exit
   end subroutine test_cli
end module test_input
