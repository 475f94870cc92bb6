!> Tests of the command line (parsing into a typed command, help, version) and of the
!> source tree's layers
module test_cli
   use testdrive, only: error_type, unittest_type, new_unittest, check, test_failed, skip_test
   use usharp_error, only: uerror => error_type, stat_usage
   use usharp_cli, only: cli_command, arg_string, parse_arguments, command_names, command_help, &
                         version_text
   use usharp_cli_args, only: accepts_option
   use usharp_cmd_deck, only: deck_command
   use test_util, only: require_exe, read_text, scratch_dir
   use usharp_filesys, only: make_dir
   use usharp_kinds, only: dp
   use usharp_strings, only: report_line_len
   implicit none
   private
   public :: collect_cli

contains

   subroutine collect_cli(testsuite)
      type(unittest_type), allocatable, intent(out) :: testsuite(:)
      testsuite = [ &
         new_unittest('arguments-into-command', test_parse), &
         new_unittest('usage-errors-name-the-argument', test_usage_errors), &
         new_unittest('every-command-has-help', test_help), &
         new_unittest('version-names-the-build', test_version), &
         new_unittest('passive-wait-unless-chosen', test_wait_policy), &
         new_unittest('folders-import-only-downward', test_layers), &
         new_unittest('predict-with-the-constants-that-made-the-data', test_predict), &
         new_unittest('predict-needs-constants', test_predict_needs_constants), &
         new_unittest('predict-simulates-a-test-without-data', test_predict_without_data), &
         new_unittest('predict-readme-a617-twice', test_predict_a617), &
         new_unittest('deck-test-and-input-swapped', test_deck_swapped), &
         new_unittest('identify-words-at-the-truth-and-a-guess', test_identify_words)]
   end subroutine collect_cli

   !> The argument list of a command line given as one string split at blanks
   function argv(line) result(args)
      character(len=*), intent(in) :: line
      type(arg_string), allocatable :: args(:)
      integer :: i, j
      allocate (args(0))
      i = 1
      do while (i <= len(line))
         if (line(i:i) == ' ') then
            i = i + 1
            cycle
         end if
         j = index(line(i:), ' ')
         if (j == 0) j = len(line) - i + 2
         args = [args, arg_string(line(i:i + j - 2))]
         i = i + j
      end do
   end function argv

   subroutine test_parse(error)
      type(error_type), allocatable, intent(out) :: error
      type(cli_command) :: cmd
      type(uerror), allocatable :: e
      call parse_arguments(argv('run -o out2 --constants best.nml --resume -q fit.nml'), cmd, e)
      call check(error, .not. allocated(e), 'run parses')
      if (allocated(error)) return
      call check(error, cmd%name == 'run' .and. cmd%input == 'fit.nml' .and. cmd%out_dir == 'out2' &
                 .and. cmd%constants == 'best.nml' .and. cmd%resume .and. cmd%quiet, 'run fields')
      if (allocated(error)) return
      call parse_arguments(argv('deck lcf decks/x.nml'), cmd, e)
      call check(error, .not. allocated(e) .and. cmd%test_name == 'lcf' .and. cmd%input == 'decks/x.nml', &
                 'deck takes a test before the input')
      if (allocated(error)) return
      call parse_arguments(argv('run --auto-resume fit.nml'), cmd, e)
      call check(error, .not. allocated(e) .and. cmd%auto_resume .and. .not. cmd%resume, 'auto-resume')
      if (allocated(error)) return
      call parse_arguments(argv('diagnose --selfcheck'), cmd, e)
      call check(error, .not. allocated(e) .and. cmd%selfcheck .and. cmd%input == '', &
                 'selfcheck needs no input')
      if (allocated(error)) return
      call parse_arguments(argv('help'), cmd, e)
      call check(error, .not. allocated(e) .and. cmd%help .and. cmd%name == '', 'help alone')
      if (allocated(error)) return
      call parse_arguments(argv('help diagnose'), cmd, e)
      call check(error, .not. allocated(e) .and. cmd%help .and. cmd%name == 'diagnose', 'help of a command')
      if (allocated(error)) return
      call parse_arguments(argv('help fitt'), cmd, e)
      call check(error, allocated(e), 'help of no command')
      if (allocated(error)) return
      deallocate (e)
      call parse_arguments(argv('simulate -t relax x.nml'), cmd, e)
      call check(error, .not. allocated(e) .and. cmd%only_test == 'relax', 'simulate -t')
      if (allocated(error)) return
      call parse_arguments(argv('run -q -- -x.nml'), cmd, e)
      call check(error, .not. allocated(e) .and. cmd%quiet .and. cmd%input == '-x.nml', &
                 "'--' ends the options")
      if (allocated(error)) return
      call parse_arguments(argv('run -- -q'), cmd, e)
      call check(error, .not. allocated(e) .and. .not. cmd%quiet .and. cmd%input == '-q', &
                 "after '--' an option's name is a file's")
      if (allocated(error)) return
      call parse_arguments(argv('identify --help --bogus'), cmd, e)
      call check(error, .not. allocated(e) .and. cmd%help .and. cmd%name == 'identify', &
                 'help ends the parsing')
   end subroutine test_parse

   subroutine test_usage_errors(error)
      type(error_type), allocatable, intent(out) :: error
      character(len=*), parameter :: lines(*) = [character(len=40) :: &
         'frobnicate x.nml', 'run --resum x.nml', 'simulate --resume x.nml', 'run', &
         'run a.nml b.nml', 'deck a b c', 'run x.nml -o', 'identify --selfcheck x.nml', '-v', &
         'predict x.nml', 'simulate -t a -t b x.nml', 'run -o a x.nml --out-dir b', &
         'deck -c a.nml -c b.nml x.nml']
      character(len=*), parameter :: expect(*) = [character(len=60) :: &
         "unknown command 'frobnicate'", 'unknown option --resum', 'unknown option --resume', &
         'no input file given', 'more than one input file', 'more than one input file', &
         '-o needs a value', 'unknown option --selfcheck', 'unknown option -v', &
         'predict needs the constants of a fit: -c best.nml', '-t is given twice', &
         '--out-dir is given twice', '-c is given twice']
      type(cli_command) :: cmd
      type(uerror), allocatable :: e
      integer :: k
      do k = 1, size(lines)
         call parse_arguments(argv(trim(lines(k))), cmd, e)
         if (.not. allocated(e)) then
            call test_failed(error, trim(lines(k))//': no usage error')
            return
         end if
         call check(error, e%stat == stat_usage .and. e%message == trim(expect(k)), &
                    trim(lines(k))//': '//e%message)
         if (allocated(error)) return
      end do
      ! An empty value, which the shell passes as its own argument
      call parse_arguments([arg_string('run'), arg_string('-o'), arg_string(''), arg_string('x.nml')], cmd, e)
      call check(error, allocated(e), "run -o '' x.nml: no usage error")
      if (allocated(error)) return
      call check(error, e%message, "-o has an empty value ('')", "run -o '' x.nml")
   end subroutine test_usage_errors

   subroutine test_help(error)
      type(error_type), allocatable, intent(out) :: error
      character(len=8) :: names(size(command_names()))
      integer :: k
      names = command_names()
      do k = 1, size(names)
         call check(error, index(command_help(trim(names(k))), 'usage: usharp '//trim(names(k))) == 1 &
                    .and. index(command_help(trim(names(k))), 'docs/reference/namelist.md') > 0, &
                    trim(names(k))//' help')
         if (allocated(error)) return
         ! The help names --force exactly where the command takes it
         call check(error, accepts_option(trim(names(k)), '--force') .eqv. &
                    index(command_help(trim(names(k))), '--force ') > 0, trim(names(k))//' help: --force')
         if (allocated(error)) return
      end do
   end subroutine test_help

   subroutine test_version(error)
      type(error_type), allocatable, intent(out) :: error
      character(len=:), allocatable :: text
      text = version_text()
      call check(error, index(text, 'compiler: GCC') > 0 .and. index(text, 'SUNDIALS: 6.') > 0 &
                 .and. index(text, 'OpenMP: ') > 0, 'version text: '//text)
   end subroutine test_version

   !> Started without OMP_WAIT_POLICY the program runs with passive waiting; a policy the
   !> user chose is kept
   subroutine test_wait_policy(error)
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: e
      character(len=:), allocatable :: exe, out
      call require_exe(exe, error)
      if (allocated(error)) return
      call make_dir(scratch_dir, e)
      out = scratch_dir//'/version.txt'
      call execute_command_line('env -u OMP_WAIT_POLICY '//exe//' --version > '//out)
      call check(error, index(read_text(out), 'wait policy passive') > 0, 'unset: '//read_text(out))
      if (allocated(error)) return
      call execute_command_line('OMP_WAIT_POLICY=active '//exe//' --version > '//out)
      call check(error, index(read_text(out), 'wait policy active') > 0, 'chosen: '//read_text(out))
   end subroutine test_wait_policy

   !> scripts/import-graph.py --check: no folder of src/ uses a module of a folder above it
   subroutine test_layers(error)
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: e
      character(len=:), allocatable :: log
      integer :: stat, cmdstat
      call execute_command_line('command -v python3 > /dev/null 2>&1', exitstat=stat, cmdstat=cmdstat)
      if (cmdstat /= 0 .or. stat /= 0) then
         call skip_test(error, 'python3 is not installed: the import graph script needs it')
         return
      end if
      call make_dir(scratch_dir, e)
      call execute_command_line('python3 scripts/import-graph.py --check --doc docs/architecture.md > '//scratch_dir// &
                                '/import-graph.txt 2>&1', exitstat=stat, cmdstat=cmdstat)
      log = read_text(scratch_dir//'/import-graph.txt')
      call check(error, cmdstat == 0 .and. stat == 0, 'scripts/import-graph.py --check: '//log)
   end subroutine test_layers

   !> predict of the thesis's run 2 tests with the constants that made their data (Table 4):
   !> RMS error under 1e-5 of the peak stress, and the files of a fit written
   subroutine test_predict(error)
      use usharp_cmd_predict, only: predict_command
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: e
      character(len=report_line_len), allocatable :: summary(:)
      character(len=*), parameter :: dir = scratch_dir//'/predict-out'
      real(dp) :: rms, rel, worst
      character(len=32) :: name
      character(len=1) :: pct
      logical :: exists
      integer :: k, ios, npts
      call predict_command('decks/thesis-run2.nml', dir, 'decks/thesis-data.nml', summary, e)
      if (allocated(e)) then
         call test_failed(error, e%message)
         return
      end if
      do k = 3, 4
         read (summary(k), *, iostat=ios) name, rms, rel, pct, worst, npts
         call check(error, ios == 0 .and. rel < 1.0e-3_dp, 'RMS/peak (%) of '//trim(summary(k)))
         if (allocated(error)) return
         ! the points compared: the rows of its .fit.txt
         call check(error, npts == data_rows(dir//'/'//trim(name)//'.fit.txt'), 'points of '//trim(summary(k)))
         if (allocated(error)) return
      end do
      inquire (file=dir//'/summary.txt', exist=exists)
      call check(error, exists, 'summary.txt written')
      if (allocated(error)) return
      inquire (file=dir//'/relax.fit.txt', exist=exists)
      call check(error, exists, 'relax.fit.txt written')
      if (allocated(error)) return
      inquire (file=dir//'/lcf.sim.txt', exist=exists)
      call check(error, exists, 'lcf.sim.txt written')
   contains
      !> The lines of a file that are not comments
      integer function data_rows(path) result(n)
         character(len=*), intent(in) :: path
         character(len=512) :: line
         integer :: u, ios
         n = 0
         open (newunit=u, file=path, status='old', action='read', iostat=ios)
         if (ios /= 0) return
         do
            read (u, '(a)', iostat=ios) line
            if (ios /= 0) exit
            if (line(1:1) /= '#') n = n + 1
         end do
         close (u)
      end function data_rows
   end subroutine test_predict

   !> predict of a deck with a test without data (a programmed history whose response is
   !> wanted): simulated with the -c constants (its stress the same as that of the same
   !> history with data, to the last digit written), a row that says so, no .fit.txt for it
   subroutine test_predict_without_data(error)
      use usharp_cmd_predict, only: predict_command
      use test_util, only: write_text
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: e
      character(len=report_line_len), allocatable :: summary(:)
      character(len=*), parameter :: dir = scratch_dir//'/predict-no-data'
      character(len=:), allocatable :: deck, a, b
      character(len=*), parameter :: relax = "history='relaxation', dt_out=1.0, levels=0.00075, 0.001, "// &
                                             "ramp_time=1.0, holds=600.0, 600.0"
      logical :: exists
      deck = write_text('predict-no-data.nml', [character(len=200) :: &
         "&model name='miller', units='ksi', temperature=866.15, tm=1800.0, youngs=22.5e3 /", &
         '&constants a1=1.0, a2=1.0e-5, b=1.0e13, c2=0.1, h1=100.0, h2=100.0, n=1.0, q=91000.0 /', &
         "&test name='relax', "//relax//", data_file='../../data/thesis/relax.sim.txt' /", &
         "&test name='wanted', "//relax//" /"])
      call predict_command(deck, dir, 'decks/thesis-data.nml', summary, e, force=.true.)
      if (allocated(e)) then
         call test_failed(error, e%message)
         return
      end if
      call check(error, index(summary(4), 'wanted') > 0 .and. index(summary(4), 'simulated only') > 0, &
                 'the row of the test without data: '//trim(summary(4)))
      if (allocated(error)) return
      inquire (file=dir//'/wanted.fit.txt', exist=exists)
      call check(error, .not. exists, 'no wanted.fit.txt')
      if (allocated(error)) return
      ! The curves after their first lines (which name the test)
      a = read_text(dir//'/relax.sim.txt')
      b = read_text(dir//'/wanted.sim.txt')
      a = a(index(a, '# columns'):)
      b = b(index(b, '# columns'):)
      call check(error, len(a) > 1000 .and. a == b, 'the response without data is the one with the -c constants')
   end subroutine test_predict_without_data

   !> predict without -c is an input error that says what is missing
   subroutine test_predict_needs_constants(error)
      use usharp_cmd_predict, only: predict_command
      use usharp_error, only: stat_input
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: e
      character(len=report_line_len), allocatable :: summary(:)
      call predict_command('decks/thesis-run2.nml', scratch_dir//'/predict-none', '', summary, e)
      call check(error, allocated(e), 'an error')
      if (allocated(error)) return
      call check(error, e%stat == stat_input .and. index(e%message, '-c') > 0, e%message)
   end subroutine test_predict_needs_constants

   !> The README's prediction of measured Alloy 617 tests (long test names, peak-stress targets,
   !> creep), run twice into one folder: a row per test and per peak-stress target, and the
   !> second run replaces the first's files as its own
   subroutine test_predict_a617(error)
      use usharp_cmd_predict, only: predict_command
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: e
      character(len=report_line_len), allocatable :: summary(:)
      character(len=*), parameter :: dir = scratch_dir//'/predict-a617'
      integer :: run, k, rows, peaks
      logical :: exists
      inquire (file='../shared/realdata/a617-950C/lcf/HTM_A19_Cycles_J2.csv', exist=exists)
      if (.not. exists) then
         call skip_test(error, 'the measured Alloy 617 data are not at ../shared/realdata')
         return
      end if
      do run = 1, 2
         call predict_command('decks/a617-950C-predict.nml', dir, 'decks/a617-950C-best.nml', &
                              summary, e)
         if (allocated(e)) then
            call test_failed(error, 'run '//achar(48 + run)//': '//e%message)
            return
         end if
         rows = 0
         peaks = 0
         do k = 1, size(summary)
            if (index(summary(k), ' %') > 0) rows = rows + 1
            if (index(summary(k), ' peaks  ') > 0) peaks = peaks + 1  ! (the name column's)
         end do
         call check(error, rows == 18 .and. peaks == 7, 'run '//achar(48 + run)//': 11 tests and '// &
                    '7 peak-stress rows in the table')
         if (allocated(error)) return
      end do
      inquire (file=dir//'/J2-2.0pct-1e-4.peaks.txt', exist=exists)
      call check(error, exists, 'J2-2.0pct-1e-4.peaks.txt written')
   end subroutine test_predict_a617

   !> `usharp deck decks/thesis-data.nml lcf` (the input before the test's name): a usage error
   !> that gives the order, not "lcf: no such input file"; nothing written
   subroutine test_deck_swapped(error)
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: e
      character(len=4096), allocatable :: written(:)
      call deck_command('lcf', 'decks/thesis-data.nml', scratch_dir//'/deck-swapped', '', written, e)
      call check(error, allocated(e), 'swapped arguments refused')
      if (allocated(error)) return
      call check(error, e%stat == stat_usage .and. index(e%message, 'lcf: no such input file; usharp '// &
                 'deck takes the test''s name first: usharp deck lcf decks/thesis-data.nml') == 1 .and. &
                 size(written) == 0, 'usage error giving the order: '//e%message)
   end subroutine test_deck_swapped
   !> identify at the constants that made noise-free data is at an optimum (what a step
   !> would take off lies within the integrator's accuracy), and at the thesis's standard
   !> guess, where A1 and A2 share two weak directions, says neither is determined (not that
   !> A1*A2 and A2/A1 each are)
   subroutine test_identify_words(error)
      use usharp_cmd_identify, only: identify_command
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: e
      character(len=report_line_len), allocatable :: summary(:)
      character(len=:), allocatable :: text
      integer :: k
      call identify_command('decks/thesis-run2.nml', scratch_dir//'/identify-truth', &
                            'decks/thesis-data.nml', summary, e, .true.)
      if (allocated(e)) then
         call test_failed(error, e%message)
         return
      end if
      call check(error, index(summary(1), 'identifiability at the optimum') == 1, trim(summary(1)))
      if (allocated(error)) return
      call identify_command('decks/thesis-run2.nml', scratch_dir//'/identify-guess', '', summary, e, .true.)
      if (allocated(e)) then
         call test_failed(error, e%message)
         return
      end if
      text = ''
      do k = 1, size(summary)
         text = text//trim(summary(k))//new_line('a')
      end do
      call check(error, index(text, 'neither A1 nor A2 is determined, nor a combination of them') > 0 &
                 .and. index(text, 'only A2/A1 is determined') == 0 .and. &
                 index(text, 'only A1*A2 is determined') == 0, text)
   end subroutine test_identify_words

end module test_cli
