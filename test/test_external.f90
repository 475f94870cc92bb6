!> Tests of the external-FE backend: the PRVAR reader, the APDL deck against the internal
!> history, the command placeholders, every failure of an external run, and a fit through
!> the ANSYS stand-in (test/ansys_standin.sh) against the internal fit
module test_external
   use testdrive, only: error_type, unittest_type, new_unittest, check, test_failed, skip_test
   use usharp_kinds, only: dp
   use usharp_error, only: uerror => error_type
   use usharp_strings, only: str, report_line_len
   use usharp_prvar, only: read_prvar
   use usharp_config, only: run_config
   use usharp_input, only: read_config
   use usharp_history, only: output_times
   use usharp_apdl, only: apdl_deck, line_len
   use usharp_external, only: run_external, expand_command
   use usharp_cmd_run, only: run_command
   use usharp_filesys, only: absolute_path, join_path, file_exists
   use test_util, only: write_text, usharp_exe, read_text, scratch_dir, check_message
   implicit none
   private
   public :: collect_external

   !> The model and constants of the deck tests (thesis units, Table 4 but H1 and n)
   character(len=*), parameter :: head(2) = [character(len=100) :: &
      "&model name='miller', units='ksi', temperature=866.15, tm=1800.0, youngs=22.5e3 /", &
      '&constants a1=0.8, a2=7.42e-5, b=1e15, c2=0.1, h1=280, h2=100, n=5.8, q=91000 /']

contains

   subroutine collect_external(testsuite)
      type(unittest_type), allocatable, intent(out) :: testsuite(:)
      testsuite = [ &
         new_unittest('prvar-page-breaks-and-titles', test_prvar), &
         new_unittest('prvar-bad-listings-rejected', test_prvar_bad), &
         new_unittest('deck-load-steps-are-history-corners', test_deck_corners), &
         new_unittest('committed-decks-regenerate', test_committed_decks), &
         new_unittest('deck-tests-sharing-constants-read-them-alike', test_deck_shared_constants), &
         new_unittest('deck-long-creep-and-tmf-refused-dt-max-per-test', test_deck_increments), &
         new_unittest('command-placeholders-quoted', test_placeholders), &
         new_unittest('external-run-failures-named', test_failures), &
         new_unittest('external-command-time-limit', test_time_limit), &
         new_unittest('external-command-gets-the-environment', test_environment), &
         new_unittest('external-failures-stop-fit-logs-intact', test_fit_failures), &
         new_unittest('standin-fit-reproduces-internal-fit', test_standin_fit)]
   end subroutine collect_external

   !> Page headers, title lines repeated after each page break, variables in any order
   subroutine test_prvar(error)
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: e
      real(dp), allocatable :: v(:, :)
      character(len=:), allocatable :: path
      character(len=200) :: lines(19)
      lines = [character(len=200) :: &
         ' ANSYS Mechanical Enterprise 2024 R2 BUILD 24.2 UP20240603 '// &
         'a page header that is much longer than any column of the listing below  PAGE 1', &
         ' /INPUT FILE= lcf.inp', &
         ' ***** POST26 VARIABLE LISTING *****', &
         '', &
         '  TIME        3 U                 2 S', &
         '              STRAIN              STRESS', &
         ' 0.10000      0.5E-05           0.1125', &
         ' 0.20000      0.1E-04           0.2250', &
         achar(12)//' ANSYS Mechanical Enterprise 2024 R2   PAGE 2', &
         ' ***** POST26 VARIABLE LISTING *****', &
         '  TIME        3 U                 2 S', &
         '              STRAIN              STRESS', &
         ' 0.30000      0.15E-04          0.3375', &
         '', &
         ' 0.40000      0.2E-04           0.4500', &
         ' ANSYS Mechanical Enterprise 2024 R2   PAGE 3', &
         '  TIME        3 U                 2 S', &
         '              STRAIN              STRESS', &
         ' 0.50000      0.25E-04          0.5625']
      path = write_text('prvar-ok.txt', lines)
      call read_prvar(path, [character(len=8) :: 'time', 'stress'], v, e)
      if (allocated(e)) then
         call test_failed(error, e%message)
         return
      end if
      call check(error, size(v, 1), 5, 'rows over three pages')
      if (allocated(error)) return
      call check(error, all(abs(v(:, 1) - [0.1_dp, 0.2_dp, 0.3_dp, 0.4_dp, 0.5_dp]) < 1e-14_dp), &
                 'time column')
      if (allocated(error)) return
      call check(error, all(abs(v(:, 2) - 1.125_dp*v(:, 1)) < 1e-14_dp), &
                 'stress found by its title in the third column')
      if (allocated(error)) return
      ! By position too
      call read_prvar(path, [character(len=8) :: '1', '2'], v, e)
      call check(error, .not. allocated(e), 'columns by position')
      if (allocated(error)) return
      call check(error, abs(v(5, 2) - 0.25e-4_dp) < 1e-18_dp, 'second column by position')
   end subroutine test_prvar

   subroutine test_prvar_bad(error)
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: e
      real(dp), allocatable :: v(:, :)
      character(len=:), allocatable :: path
      path = write_text('prvar-garbled.txt', [character(len=60) :: '  TIME   STRESS', &
         ' 0.1  1.0', ' 0.2  1.#INF0', ' 0.3 3.0'])
      call read_prvar(path, [character(len=8) :: 'TIME', 'STRESS'], v, e)
      call check_message(error, e, 'prvar-garbled.txt:3: garbled row')
      if (allocated(error)) return
      path = write_text('prvar-count.txt', [character(len=60) :: '  TIME   STRESS', &
         ' 0.1  1.0', ' 0.2  2.0  7.0'])
      call read_prvar(path, [character(len=8) :: 'TIME', 'STRESS'], v, e)
      call check_message(error, e, 'prvar-count.txt:3: garbled row: 3 numbers where the titles name 2')
      if (allocated(error)) return
      path = write_text('prvar-title.txt', [character(len=60) :: '  TIME   STRAIN', ' 0.1  1.0'])
      call read_prvar(path, [character(len=8) :: 'TIME', 'STRESS'], v, e)
      call check_message(error, e, "no column titled 'STRESS' (titles: TIME STRAIN)")
      if (allocated(error)) return
      path = write_text('prvar-empty.txt', [character(len=60) :: ' ***** POST26 VARIABLE LISTING *****'])
      call read_prvar(path, [character(len=8) :: 'TIME', 'STRESS'], v, e)
      call check_message(error, e, 'no data rows')
   end subroutine test_prvar_bad

   !> The deck's load steps (TIME and the top-face displacement or force) are the corners of
   !> the history the internal driver integrates, to the last bit
   subroutine test_deck_corners(error)
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: e
      type(run_config) :: cfg
      character(len=line_len), allocatable :: lines(:)
      character(len=:), allocatable :: path, late
      real(dp), allocatable :: t(:), v(:), tw(:), vw(:)
      integer :: i, k, nt, nv, c
      real(dp) :: x
      path = write_text('deck-corners.nml', [character(len=120) :: &
         "&model temperature = 866.15, tm = 1800.0, youngs = 22.5e3, poisson = 0.3 /", &
         "&constants a1 = 0.8, a2 = 7.42e-5, b = 1.0e15, c2 = 0.1, h1 = 280.0, h2 = 100.0,", &
         "  n = 5.8, q = 91000.0 /", &
         "&solver dt_init = 0.05, dt_min = 1e-7, dt_max = 0.2 /", &
         "&test name = 'lcf', history = 'thesis_lcf' /", &
         "&test name = 'relax', history = 'relaxation' /", &
         "&test name = 'ratchet', history = 'ratchet' /", &
         "&test name = 'cyc', history = 'cyclic', strain_range = 0.008, strain_rate = 1e-3,", &
         "  cycles = 3, hold_max = 30.0 /", &
         "&test name = 'creep', history = 'creep', stress = 15.0, duration = 1000.0 /", &
         "&test name = 'late', history = 'file', file = 'deck-late.csv' /"])
      ! A recording from t = 10 s whose strain starts at 1e-3: the deck's times run from its
      ! start, and a load step 0 puts the start value on within 1e-6 of the first segment
      late = write_text('deck-late.csv', [character(len=20) :: 'time,strain', '10,0.001', '20,0.004', &
                                          '40,-0.004', '50,0'])
      call read_config(path, cfg, e)
      if (allocated(e)) then
         call test_failed(error, e%message)
         return
      end if
      do i = 1, size(cfg%tests)
         call apdl_deck(cfg, cfg%tests(i), 'test', lines, e)
         if (allocated(e)) then
            call test_failed(error, e%message)
            return
         end if
         allocate (t(0), v(0))
         do k = 1, size(lines)
            if (lines(k)(1:5) == 'TIME,') then
               read (lines(k)(6:), *) x
               t = [t, x]
            else if (lines(k)(1:7) == 'D,5,UZ,' .or. lines(k)(1:7) == 'F,5,FZ,') then
               c = index(lines(k)(8:), ',')
               read (lines(k)(8:6 + c), *) x
               if (lines(k)(1:1) == 'F') x = 4.0_dp*x  ! a quarter of the unit-face force per node
               v = [v, x]
            else if (lines(k)(1:7) == 'DELTIM,' .and. .not. (cfg%tests(i)%hist%v(1) /= 0.0_dp .and. size(t) == 1)) then
               ! (load step 0 has its own: one step over its microsecond)
               call check(error, trim(lines(k)) == 'DELTIM,5.0E-002,1.0E-007,2.0E-001', &
                          'increments from &solver: '//trim(lines(k)))
               if (allocated(error)) return
            end if
         end do
         associate (h => cfg%tests(i)%hist)
            if (h%v(1) /= 0.0_dp) then
               tw = [1.0e-6_dp*(h%t(2) - h%t(1)), h%t(2:) - h%t(1)]
               vw = [h%v(1), h%v(2:)]
            else
               tw = h%t(2:) - h%t(1)
               vw = h%v(2:)
            end if
         end associate
         nt = size(cfg%tests(i)%hist%t)
         nv = size(v)
         call check(error, size(t) == size(tw) .and. nv == size(tw), "test '"//cfg%tests(i)%name// &
                    "': "//str(size(t))//' load steps for '//str(nt)//' corners')
         if (allocated(error)) return
         call check(error, all(t == tw) .and. all(v == vw), &
                    "test '"//cfg%tests(i)%name//"': load steps differ from the history's corners")
         if (allocated(error)) return
         if (cfg%tests(i)%name == 'late') call check(error, size(t) == 4 .and. t(1) == 1.0e-6_dp*10.0_dp .and. &
            t(4) == 40.0_dp .and. v(1) == 1.0e-3_dp, 'the recording from 10 s: '//str(size(t))//' load steps')
         if (allocated(error)) return
         call check(error, any(lines == 'TB,USER,1,1,13') .and. any(lines == 'TB,STATE,1,,13') .and. &
                    any(lines == 'TUNIF,8.6615E+002') .and. any(lines == '(E12.5)'), &
                    'material and temperature commands')
         if (allocated(error)) return
         deallocate (t, v)
      end do
   end subroutine test_deck_corners

   !> A creep step of 1e6 s at &solver dt_max = 0.15 s would be 6.7e6 ANSYS increments: refused
   !> naming the load step and dt_max, before the folder is made; with the test's own dt_max
   !> of 100 s its load step has DELTIM max 100 and the cyclic test keeps 0.15. A temperature
   !> cycle, which the isothermal deck would lose, is refused
   subroutine test_deck_increments(error)
      use usharp_cmd_deck, only: deck_command
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: e
      character(len=4096), allocatable :: written(:)
      character(len=:), allocatable :: deck, text
      character(len=*), parameter :: dir = scratch_dir//'/increments-decks'
      character(len=*), parameter :: creep = "&test name='creep', history='creep', stress=10.0, "// &
                                             "ramp_time=10.0, duration=1.0e6"
      call execute_command_line('rm -rf '//dir)
      deck = write_text('increments.nml', [character(len=120) :: head, creep//' /', &
                        "&test name='cyc', history='cyclic', strain_range=0.01, strain_rate=1e-3 /"])
      call deck_command(deck, '', dir, '', written, e)
      call check_message(error, e, "test 'creep': load step 2 lasts 1.00E+06 s: at dt_max = 0.150 s "// &
                         'at least 6.7E+06 increments')
      if (allocated(error)) return
      call check(error, index(e%message, 'its own dt_max') > 0 .and. .not. file_exists(dir), e%message)
      if (allocated(error)) return
      deck = write_text('increments.nml', [character(len=120) :: head, creep//', dt_max=100.0 /', &
                        "&test name='cyc', history='cyclic', strain_range=0.01, strain_rate=1e-3 /"])
      call deck_command(deck, '', dir, '', written, e)
      if (allocated(e)) then
         call test_failed(error, e%message)
         return
      end if
      text = read_text(dir//'/creep.inp')
      call check(error, index(text, 'DELTIM,1.0E-001,1.0E-008,1.0E+002') > 0, 'creep DELTIM: '//text(index(text, 'DELTIM'):))
      if (allocated(error)) return
      text = read_text(dir//'/cyc.inp')
      call check(error, index(text, 'DELTIM,1.0E-001,1.0E-008,1.5E-001') > 0, 'cyclic DELTIM: '//text(index(text, 'DELTIM'):))
      if (allocated(error)) return
      deck = write_text('increments-tmf.nml', [character(len=160) :: head, &
         "&test name='tmf', history='cyclic', strain_range=0.005, strain_rate=1e-4, "// &
         "tmf_temperatures=873.15, 1223.15 /"])
      call deck_command(deck, '', dir//'-tmf', '', written, e)
      call check_message(error, e, "test 'tmf': its temperature cycle (tmf_temperatures) would be lost")
   end subroutine test_deck_increments

   !> Tests that share one constants file read it alike: another format or another
   !> temperature's D0 for one of them is refused; with a file each, each holds its own
   !> (the D0 of a test at 900 K, that of simulate's header)
   subroutine test_deck_shared_constants(error)
      use usharp_cmd_deck, only: deck_command
      use usharp_cmd_simulate, only: simulate_command
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: e
      character(len=4096), allocatable :: written(:)
      character(len=:), allocatable :: deck, text
      real(dp) :: d0, v, last
      integer :: k, u, ios
      do k = 1, 2
         deck = write_text('shared.nml', [character(len=120) :: head, &
            "&test name='lcf', history='thesis_lcf' /", &
            "&test name='relax', history='relaxation', levels=0.00075, holds=60.0, "// &
            trim(merge("constants_format='(ES24.16)'", "temperature=900.0           ", k == 1))//' /'])
         call deck_command(deck, '', scratch_dir//'/shared-decks', '', written, e, .true.)
         call check_message(error, e, "&test #1 'lcf' and &test #2 'relax' read one constants "// &
                            'file, Constants.txt, that would hold other numbers for each')
         if (allocated(error)) return
      end do
      deck = write_text('own.nml', [character(len=120) :: head, &
         "&test name='lcf', history='thesis_lcf' /", &
         "&test name='relax', history='relaxation', levels=0.00075, holds=60.0, temperature=900.0,", &
         "  constants_file='relax-constants.txt' /"])
      call deck_command(deck, '', scratch_dir//'/own-decks', '', written, e, .true.)
      if (allocated(e)) then
         call test_failed(error, e%message)
         return
      end if
      call simulate_command(deck, scratch_dir//'/own-sim', written, e, force=.true.)
      if (allocated(e)) then
         call test_failed(error, e%message)
         return
      end if
      text = read_text(scratch_dir//'/own-sim/relax.sim.txt')
      text = text(index(text, 'D0 = ') + 5:)
      read (text(:index(text, ' ') - 1), *) d0
      ! the constants file's last number is D0
      open (newunit=u, file=scratch_dir//'/own-decks/relax-constants.txt', status='old', action='read')
      do
         read (u, *, iostat=ios) v
         if (ios /= 0) exit
         last = v
      end do
      close (u)
      call check(error, abs(last - d0) <= 1.0e-4_dp*d0, 'the D0 of relax at 900 K: '// &
                 str(last)//' against '//str(d0))
   end subroutine test_deck_shared_constants

   !> decks/ansys holds what `usharp deck decks/thesis-data.nml -o decks/ansys` writes now
   subroutine test_committed_decks(error)
      use usharp_cmd_deck, only: deck_command
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: e
      character(len=4096), allocatable :: written(:)
      character(len=:), allocatable :: new, old
      integer :: k
      call deck_command('decks/thesis-data.nml', '', scratch_dir//'/decks', '', written, e)
      if (allocated(e)) then
         call test_failed(error, e%message)
         return
      end if
      call check(error, size(written), 4, 'three decks and the constants file')
      if (allocated(error)) return
      do k = 1, size(written)
         new = read_text(trim(written(k)))
         old = read_text('decks/ansys/'//trim(written(k)(index(written(k), '/', back=.true.) + 1:)))
         if (index(written(k), '.inp') > 0) then
            ! the second line names the output folder
            new = after_lines(new, 2)
            old = after_lines(old, 2)
         end if
         call check(error, len(old) > 0 .and. old == new, trim(written(k))// &
                    ' differs from the one in decks/ansys')
         if (allocated(error)) return
      end do
   contains
      function after_lines(text, n) result(rest)
         character(len=*), intent(in) :: text
         integer, intent(in) :: n
         character(len=:), allocatable :: rest
         integer :: i
         rest = text
         do i = 1, n
            rest = rest(index(rest, new_line('a')) + 1:)
         end do
      end function after_lines
   end subroutine test_committed_decks

   subroutine test_placeholders(error)
      type(error_type), allocatable, intent(out) :: error
      character(len=:), allocatable :: cmd
      cmd = expand_command('sh {input_dir}/run.sh {test} < {constants} > {output} {other}', &
                           "/w/it's here", '/w/c.txt', '/w/o u t.txt', '/in dir', 'lcf')
      call check(error, cmd, "sh '/in dir'/run.sh lcf < '/w/c.txt' > '/w/o u t.txt' {other}", &
                 'placeholders replaced by quoted paths')
      if (allocated(error)) return
      cmd = expand_command('cd {work}', "/w/it's here", '', '', '', '')
      call check(error, cmd, "cd '/w/it'\''s here'", 'a quote inside a path')
   end subroutine test_placeholders

   !> A short relaxation test with its data, run by a command; returns the config
   subroutine external_config(name, command, extra, cfg, error)
      character(len=*), intent(in) :: name, command, extra
      type(run_config), intent(out) :: cfg
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: e
      character(len=:), allocatable :: path
      integer :: k
      ! Stress only: the short relaxation history is not data/thesis's, whose strain column
      ! would refuse it (check_programme)
      path = write_text(name//'-relax.csv', [character(len=40) :: 'time,stress', &
                        (str(k)//','//str(12 - k/4), k=0, 22)])
      path = write_text(name//'.nml', [character(len=4000) :: &
         "&model temperature = 866.15, tm = 1800.0, youngs = 22.5e3, poisson = 0.3 /", &
         "&constants a1 = 0.8, a2 = 7.42e-5, b = 1.0e15, c2 = 0.1, h1 = 280.0, h2 = 100.0,", &
         "  n = 5.8, q = 91000.0 /", &
         "&fit fitted = 'H1', 'n', max_failures = 3, max_evals = 6 /", &
         "&output out_dir = '"//name//"-out' /", &
         "&test name = 'relax', history = 'relaxation', holds = 10.0, 10.0,", &
         "  data_file = '"//name//"-relax.csv',", &
         "  backend = 'external', command = '"//command//"' "//extra//" /"])
      call read_config(path, cfg, e)
      if (allocated(e)) call test_failed(error, e%message)
   end subroutine external_config

   subroutine run_one(cfg, e)
      type(run_config), intent(in) :: cfg
      type(uerror), allocatable, intent(out) :: e
      real(dp), allocatable :: t(:), s(:)
      t = output_times(cfg%tests(1)%hist, cfg%tests(1)%dt_out)
      allocate (s(size(t)))
      call run_external(cfg%tests(1)%ext, cfg%model, cfg%units, cfg%tests(1)%hist, 'relax', &
                        cfg%base_dir, cfg%out_dir, '1', t, s, e)
   end subroutine run_one

   !> Non-zero exit, no output, short output, garbled output: each an error that says so
   subroutine test_failures(error)
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: e
      type(run_config) :: cfg
      call external_config('ext-exit', 'echo solver licence missing >&2; exit 3', '', cfg, error)
      if (allocated(error)) return
      call run_one(cfg, e)
      call check_message(error, e, 'command failed with exit status 3: solver licence missing')
      if (allocated(error)) return
      call external_config('ext-nooutput', 'true', '', cfg, error)
      if (allocated(error)) return
      call run_one(cfg, e)
      call check_message(error, e, 'command did not write its output file relax_prvar.txt')
      if (allocated(error)) return
      call external_config('ext-short', &
         'printf "  TIME STRESS\n 0.5 1.0\n 1.0 2.0\n 1.5 2.5\n" > {output}', '', cfg, error)
      if (allocated(error)) return
      call run_one(cfg, e)
      call check_message(error, e, 'short output: data cover ')
      if (allocated(error)) return
      call external_config('ext-garbled', &
         'printf "  TIME STRESS\n 0.5 1.0\n 1.0 2.0e\n 1.5 2.5\n" > {output}', '', cfg, error)
      if (allocated(error)) return
      call run_one(cfg, e)
      call check_message(error, e, 'relax_prvar.txt:3: garbled row')
      if (allocated(error)) return
      call check(error, file_exists(join_path(cfg%out_dir, 'work/relax.1/usharp-command.sh')), &
                 'the work folder of a failed run is kept')
      if (allocated(error)) return
      ! Plain columns with the unit of the output converted
      call external_config('ext-columns', &
         'printf "time,stress\n0,0\n15,3.4473786465841805\n30,6.894757293168361\n" > {output}', &
         ", output_format = 'columns', output_time = 'time', output_stress = 'stress', "// &
         "output_unit = 'MPa'", cfg, error)
      if (allocated(error)) return
      block
         real(dp), allocatable :: t(:), s(:)
         t = output_times(cfg%tests(1)%hist, cfg%tests(1)%dt_out)
         allocate (s(size(t)))
         call run_external(cfg%tests(1)%ext, cfg%model, cfg%units, cfg%tests(1)%hist, 'relax', &
                           cfg%base_dir, cfg%out_dir, '2', t, s, e)
         if (allocated(e)) then
            call test_failed(error, e%message)
            return
         end if
         call check(error, abs(s(size(s)) - 22.0_dp/30.0_dp) < 1e-12_dp, &
                    'MPa listing interpolated and converted to ksi')
         if (allocated(error)) return
         call check(error, .not. file_exists(join_path(cfg%out_dir, 'work/relax.2')), &
                    'the work folder of a good run is removed')
      end block
   end subroutine test_failures

   subroutine test_time_limit(error)
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: e
      type(run_config) :: cfg
      integer(8) :: c0, c1, rate
      call external_config('ext-slow', 'sleep 30', ', time_limit = 1.0', cfg, error)
      if (allocated(error)) return
      call system_clock(c0, rate)
      call run_one(cfg, e)
      call system_clock(c1)
      call check_message(error, e, 'command ran past its time_limit of 1.00000 s and was stopped')
      if (allocated(error)) return
      call check(error, real(c1 - c0, dp)/real(rate, dp) < 10.0_dp, 'stopped near the limit')
   end subroutine test_time_limit

   !> The command runs with usharp's environment (an FE code needs its PATH and licence
   !> variables), not an empty one
   subroutine test_environment(error)
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: e
      type(run_config) :: cfg
      character(len=180) :: value
      character(len=:), allocatable :: name
      integer :: length, status
      name = 'HOME'
      call get_environment_variable(name, value, length, status)
      if (status /= 0 .or. length == 0) then
         ! dash gives an unset PATH a default of its own: usharp's must differ from it
         name = 'PATH'
         call get_environment_variable(name, value, length, status)
      end if
      if (status /= 0 .or. length == 0) then
         call skip_test(error, 'neither HOME nor PATH is set (or fits 180 characters) here')
         return
      end if
      call external_config('ext-env', 'echo "'//name//' is [$'//name//']" >&2; exit 4', '', cfg, &
                           error)
      if (allocated(error)) return
      call run_one(cfg, e)
      call check_message(error, e, 'command failed with exit status 4: '//name//' is ['// &
                         trim(value)//']')
   end subroutine test_environment

   !> Failures are penalised and logged by evaluation; max_failures in a row stop the fit; the
   !> command's own writes (stdout, stderr, files named like the logs) never reach the logs
   subroutine test_fit_failures(error)
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: e
      type(run_config) :: cfg
      character(len=report_line_len), allocatable :: summary(:)
      character(len=:), allocatable :: fom, log, dir
      integer :: k, n
      call external_config('ext-fail', 'echo noise; echo 9.99 > FOM.TXT; echo bad > GUESS.TXT; '// &
         'echo more noise >&2; exit 2', '', cfg, error)
      if (allocated(error)) return
      dir = cfg%out_dir
      call run_command(cfg%path, '', '', .false., summary, e, force=.true.)
      call check_message(error, e, 'fit aborted: 3 failed evaluations in a row (max_failures); '// &
                         "last: test 'relax': external run")
      if (allocated(error)) return
      log = read_text(join_path(dir, 'fit.log'))
      call check(error, index(log, 'evaluation 2: penalty 2.000E+10: test ''relax'': external run') > 0, &
                 'fit.log names the evaluation and the reason: '//log)
      if (allocated(error)) return
      fom = read_text(join_path(dir, 'FOM.TXT'))
      n = 0
      do k = 1, len(fom)
         if (fom(k:k) == new_line('a')) n = n + 1
      end do
      call check(error, n == 3 .and. fom == repeat(' 0.20000E+11'//new_line('a'), 3), &
                 'FOM.TXT holds the three penalties and nothing else: '//fom)
      if (allocated(error)) return
      call check(error, index(read_text(join_path(dir, 'GUESS.TXT')), 'bad') == 0, &
                 'GUESS.TXT untouched by the command')
   end subroutine test_fit_failures

   !> The stand-in ANSYS run reproduces the internal fit: the same objective at every
   !> evaluation to 1e-6 relative, the same number of evaluations
   subroutine test_standin_fit(error)
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: e
      character(len=report_line_len), allocatable :: summary(:)
      character(len=:), allocatable :: exe, standin, nml, p_int, p_ext, ext
      real(dp), allocatable :: f_int(:), f_ext(:)
      integer :: k
      exe = usharp_exe()
      if (len(exe) == 0) then
         call skip_test(error, 'the usharp executable was not found beside the tester')
         return
      end if
      exe = absolute_path(exe)
      standin = absolute_path('test/ansys_standin.sh')
      nml = absolute_path('data/thesis')
      p_int = write_text('standin-internal.nml', fit_lines('standin-internal', ''))
      ext = ", backend = 'external', constants_format = '(ES24.16)', command = 'sh "// &
            standin//' '//exe//" {input_dir}/standin-internal.nml {test}'"
      p_ext = write_text('standin-external.nml', fit_lines('standin-external', ext))
      call run_command(p_int, '', '', .false., summary, e, force=.true.)
      if (allocated(e)) then
         call test_failed(error, 'internal fit: '//e%message)
         return
      end if
      call run_command(p_ext, '', '', .false., summary, e, force=.true.)
      if (allocated(e)) then
         call test_failed(error, 'external fit: '//e%message)
         return
      end if
      f_int = fom_values(join_path(scratch_dir, 'standin-internal-out/fit.journal'))
      f_ext = fom_values(join_path(scratch_dir, 'standin-external-out/fit.journal'))
      call check(error, size(f_int) == size(f_ext) .and. count(f_int < 1.0e9_dp) > 50, &
                 'evaluations: internal '//str(size(f_int))//', external '//str(size(f_ext))// &
                 ', not penalised '//str(count(f_int < 1.0e9_dp)))
      if (allocated(error)) return
      k = maxloc(abs(f_ext - f_int)/f_int, 1)
      call check(error, abs(f_ext(k) - f_int(k))/f_int(k) < 1.0e-6_dp, 'evaluation '//str(k)// &
                 ': internal '//str(f_int(k))//', external '//str(f_ext(k)))
      if (allocated(error)) return
      call check(error, abs(minval(f_ext) - minval(f_int))/minval(f_int) < 1.0e-6_dp, &
                 'best objective')
   contains
      function fit_lines(name, extra) result(lines)
         character(len=*), intent(in) :: name, extra
         character(len=400), allocatable :: lines(:)
         lines = [character(len=4000) :: &
            "&model temperature = 866.15, tm = 1800.0, youngs = 22.5e3, poisson = 0.3 /", &
            "&constants a1 = 1.0, a2 = 1.0e-5, b = 1.0e13, c2 = 0.1, h1 = 100.0, h2 = 100.0,", &
            "  n = 1.0, q = 91000.0 /", &
            "&fit fitted = 'A1', 'A2', 'B', 'C2', 'H1', 'H2', 'n', max_evals = 60, log_search = .true. /", &
            "&output out_dir = '"//name//"-out' /", &
            "&test name = 'lcf', history = 'thesis_lcf', dt_out = 1.0, weighting = 'threshold',", &
            "  sig = 14.0, data_file = '"//nml//"/lcf.sim.txt'"//extra//" /", &
            "&test name = 'relax', history = 'relaxation', dt_out = 1.0, weighting = 'relaxation',", &
            "  data_file = '"//nml//"/relax.sim.txt'"//extra//" /"]
      end function fit_lines
   end subroutine test_standin_fit

   !> The objective of every evaluation from a fit.journal
   function fom_values(path) result(f)
      character(len=*), intent(in) :: path
      real(dp), allocatable :: f(:)
      character(len=4096) :: line
      integer :: unit, ios, k, status
      real(dp) :: x
      allocate (f(0))
      open (newunit=unit, file=path, status='old', action='read', iostat=ios)
      if (ios /= 0) return
      do
         read (unit, '(a)', iostat=ios) line
         if (ios /= 0) exit
         if (line(1:1) == '#') cycle  ! the fingerprint
         read (line, *) k, status, x
         f = [f, x]
      end do
      close (unit)
   end function fom_values
end module test_external
