!> usharp command line: argument parsing and dispatch only
program usharp_main
   use, intrinsic :: iso_c_binding, only: c_int
   use, intrinsic :: iso_fortran_env, only: error_unit, output_unit
   use usharp_kinds, only: dp
   use usharp_strings, only: str, real_str
   use usharp_error, only: error_type, stat_usage
   use usharp_version, only: usharp_version_string
   use usharp_cmd_simulate, only: simulate_command
   use usharp_cmd_run, only: run_command
   use usharp_cmd_deck, only: deck_command
   use usharp_cmd_identify, only: identify_command
   use usharp_cmd_design, only: design_command
   use usharp_cmd_diagnose, only: diagnose_command, selfcheck_command
   implicit none

   character(len=:), allocatable :: command, input, out_dir, constants, arg, first, only_test
   character(len=256), allocatable :: written(:)
   character(len=200), allocatable :: summary(:)
   type(error_type), allocatable :: error
   logical :: resume, quiet, selfcheck
   integer :: i, nargs

   interface
      function c_isatty(fd) bind(C, name='isatty') result(r)
         import :: c_int
         integer(c_int), value :: fd
         integer(c_int) :: r
      end function c_isatty
   end interface

   nargs = command_argument_count()
   if (nargs == 0) call usage_exit(main_usage())
   command = get_arg(1)
   select case (command)
   case ('-h', '--help')
      write (output_unit, '(a)') main_usage()
      stop
   case ('-V', '--version')
      call print_version()
      stop
   case ('simulate', 'run', 'deck', 'identify', 'design', 'diagnose')
   case default
      call usage_exit(main_usage(), "unknown command '"//command//"'")
   end select

   input = ''
   first = ''
   only_test = ''
   out_dir = ''
   constants = ''
   resume = .false.
   quiet = .false.
   selfcheck = .false.
   i = 2
   do while (i <= nargs)
      arg = get_arg(i)
      select case (arg)
      case ('-h', '--help')
         write (output_unit, '(a)') command_usage(command)
         stop
      case ('-V', '--version')
         call print_version()
         stop
      case ('-o', '--out-dir')
         out_dir = option_value()
      case ('-c', '--constants')
         constants = option_value()
      case ('-t', '--test')
         if (command /= 'simulate') call usage_exit(command_usage(command), 'unknown option '//arg)
         only_test = option_value()
      case ('--resume')
         if (command /= 'run') call usage_exit(command_usage(command), 'unknown option '//arg)
         resume = .true.
      case ('-q', '--quiet')
         quiet = .true.
      case ('--selfcheck')
         if (command /= 'diagnose') call usage_exit(command_usage(command), 'unknown option '//arg)
         selfcheck = .true.
      case default
         if (arg(1:1) == '-') call usage_exit(command_usage(command), 'unknown option '//arg)
         if (len(input) > 0 .and. (command /= 'deck' .or. len(first) > 0)) &
            call usage_exit(command_usage(command), 'more than one input file')
         ! deck takes an optional test name before the input file
         first = input
         input = arg
      end select
      i = i + 1
   end do
   if (len(input) == 0 .and. .not. selfcheck) call usage_exit(command_usage(command), 'no input file given')

   select case (command)
   case ('simulate', 'deck')
      if (command == 'simulate') then
         call simulate_command(input, out_dir, written, error, constants, only_test)
      else
         call deck_command(input, first, out_dir, constants, written, error)
      end if
      if (allocated(error)) call error_exit(error)
      if (.not. quiet) then
         do i = 1, size(written)
            write (output_unit, '(a)') 'wrote '//trim(written(i))
         end do
      end if
   case ('identify', 'design', 'diagnose')
      if (command == 'identify') then
         call identify_command(input, out_dir, constants, summary, error)
      else if (command == 'design') then
         call design_command(input, out_dir, constants, summary, error)
      else if (selfcheck) then
         call selfcheck_command(input, out_dir, summary, error)
      else
         call diagnose_command(input, out_dir, constants, summary, error)
      end if
      if (allocated(error)) call error_exit(error)
      do i = 1, size(summary)
         write (output_unit, '(a)') trim(summary(i))
      end do
   case ('run')
      ! The progress line only on a terminal and without --quiet
      if (.not. quiet .and. c_isatty(2_c_int) == 1) then
         call run_command(input, out_dir, constants, resume, summary, error, show_progress)
         write (error_unit, '(a)') ''
      else
         call run_command(input, out_dir, constants, resume, summary, error)
      end if
      if (allocated(error)) call error_exit(error)
      do i = 1, size(summary)
         write (output_unit, '(a)') trim(summary(i))
      end do
   end select

contains

   subroutine show_progress(nevals, best, seconds)
      integer, intent(in) :: nevals
      real(dp), intent(in) :: best, seconds
      write (error_unit, '(a)', advance='no') achar(13)//'usharp run: '//str(nevals)// &
         ' evaluations, best '//real_str(best, 'es11.4')//', '//real_str(seconds, 'f10.1')//' s   '
      flush (error_unit)
   end subroutine show_progress

   function option_value() result(val)
      character(len=:), allocatable :: val
      i = i + 1
      if (i > nargs) call usage_exit(command_usage(command), arg//' needs a value')
      val = get_arg(i)
   end function option_value

   function get_arg(k) result(val)
      integer, intent(in) :: k
      character(len=:), allocatable :: val
      integer :: length
      call get_command_argument(k, length=length)
      allocate (character(len=length) :: val)
      if (length > 0) call get_command_argument(k, val)
   end function get_arg

   subroutine print_version()
      write (output_unit, '(a)') 'usharp '//usharp_version_string
   end subroutine print_version

   subroutine usage_exit(text, message)
      character(len=*), intent(in) :: text
      character(len=*), intent(in), optional :: message
      if (present(message)) write (error_unit, '(a)') 'usharp: '//message
      write (error_unit, '(a)') text
      stop stat_usage, quiet=.true.
   end subroutine usage_exit

   subroutine error_exit(err)
      type(error_type), intent(in) :: err
      write (error_unit, '(a)') 'usharp: error: '//err%message
      stop err%stat, quiet=.true.
   end subroutine error_exit

   function main_usage() result(text)
      character(len=:), allocatable :: text
      character(len=*), parameter :: nl = new_line('a')
      text = 'usage: usharp <command> [options] <input.nml>'//nl//nl//'commands:'//nl// &
         '  run        fit the constants of &fit to the data of every &test'//nl// &
         '  simulate   simulate every &test, write <out_dir>/<test>.sim.txt'//nl// &
         '  deck       write the ANSYS APDL input deck of a &test: <out_dir>/<test>.inp'//nl// &
         '  identify   identifiability of the &fit constants at the input''s constants'//nl// &
         '  design     rank candidate tests by how well they would determine the constants'//nl// &
         '  diagnose   where a fit falls short, which unmodelled effect causes it, how far'//nl// &
         '             adding it closes the gap (also on held-out tests)'//nl//nl// &
         'options:'//nl// &
         '  -h, --help     show this help (after a command: the command''s help)'//nl// &
         '  -V, --version  show the version'//nl//nl// &
         'exit codes: 0 success, 1 input error, 2 usage error, 3 failed simulation or fit, '// &
         '4 output not writable'
   end function main_usage

   function command_usage(cmd) result(text)
      character(len=*), intent(in) :: cmd
      character(len=:), allocatable :: text
      character(len=*), parameter :: nl = new_line('a')
      select case (cmd)
      case ('run')
         text = 'usage: usharp run [options] <fit.nml>'//nl//nl// &
            'Fits the constants named in &fit to the data files of the &test groups and'//nl// &
            'writes GUESS.TXT, FOM.TXT, SUMS.TXT, fit.log, fit.journal, best.nml, summary.txt'//nl// &
            'and <test>.sim.txt / <test>.fit.txt into the output folder.'//nl//nl//'options:'//nl// &
            '  -o, --out-dir DIR     write to DIR instead of &output out_dir'//nl// &
            '  -c, --constants FILE  start from the &constants of FILE (e.g. a best.nml)'//nl// &
            '      --resume          continue a killed run from its fit.journal'//nl// &
            '  -q, --quiet           no progress line on stderr'//nl// &
            '  -h, --help            show this help'//nl// &
            '  -V, --version         show the version'
      case ('identify')
         text = 'usage: usharp identify [options] <fit.nml>'//nl//nl// &
            'Reports, at the &constants of the input (or of --constants FILE, e.g. a best.nml),'//nl// &
            'how well the tests with their data determine the constants named in &fit: the'//nl// &
            'singular values of the scaled Jacobian, 95 % intervals, correlations, constants at'//nl// &
            'a bound and the poorly determined directions. Writes <out_dir>/identify.txt.'//nl//nl// &
            'options:'//nl// &
            '  -o, --out-dir DIR     write to DIR instead of &output out_dir'//nl// &
            '  -c, --constants FILE  use the &constants of FILE (e.g. a best.nml from run)'//nl// &
            '  -h, --help            show this help'//nl// &
            '  -V, --version         show the version'
      case ('design')
         text = 'usage: usharp design [options] <design.nml>'//nl//nl// &
            'Simulates every &test with the known &constants (or those of --constants FILE) and'//nl// &
            'predicts, for a stress noise of &design noise, how well the current tests (the'//nl// &
            'groups without candidate = .true.) and each combination with the candidate tests'//nl// &
            'determine the constants named in &fit: predicted 95 % intervals, the gain in log'//nl// &
            'det of the information, and the best matrices of up to &design max_tests tests.'//nl// &
            'Writes <out_dir>/design.txt.'//nl//nl// &
            'options:'//nl// &
            '  -o, --out-dir DIR     write to DIR instead of &output out_dir'//nl// &
            '  -c, --constants FILE  use the &constants of FILE as the known constants'//nl// &
            '  -h, --help            show this help'//nl// &
            '  -V, --version         show the version'
      case ('diagnose')
         text = 'usage: usharp diagnose [options] <fit.nml>'//nl// &
            '       usharp diagnose --selfcheck [options] [<selfcheck.nml>]'//nl//nl// &
            'Diagnoses the fit at the &constants of --constants FILE (the best.nml of a run):'//nl// &
            'fits the tests not in &diagnose holdout without any effect, splits the residual by'//nl// &
            'test, history class, cycle and elastic/inelastic points against the noise level of'//nl// &
            'the data, screens every catalogue effect (score test), refits the leading ones'//nl// &
            '(AIC/BIC, 95 % intervals) and predicts the held-out tests with them. Writes'//nl// &
            '<out_dir>/diagnose/report.md, regions.csv, effects.csv, residuals.csv and plots.'//nl// &
            'Effects: compliance, lag, temperature, scatter, initial, shift, softening,'//nl// &
            'backstress2.'//nl//nl// &
            'With --selfcheck: injects each effect into synthetic data (the built-in matrix,'//nl// &
            'written to <out_dir>/selfcheck.nml, or the given file), fits without it, diagnoses'//nl// &
            'and prints the confusion table (<out_dir>/selfcheck.md).'//nl//nl// &
            'options:'//nl// &
            '  -o, --out-dir DIR     write to DIR instead of &output out_dir'//nl// &
            '  -c, --constants FILE  the fitted constants (the best.nml of usharp run)'//nl// &
            '      --selfcheck       the self-check on synthetic data'//nl// &
            '  -h, --help            show this help'//nl// &
            '  -V, --version         show the version'
      case ('deck')
         text = 'usage: usharp deck [options] [<test>] <input.nml>'//nl//nl// &
            'Writes the ANSYS APDL input deck of the &test named <test> (of every test when'//nl// &
            'none is named) as <out_dir>/<test>.inp, and the constants file it reads (the'//nl// &
            'constants_file of the test, Constants.txt by default) with the input''s constants.'//nl// &
            'The deck needs an ANSYS linked with the usharp USERMAT (see the README).'//nl//nl// &
            'options:'//nl// &
            '  -o, --out-dir DIR     write to DIR instead of &output out_dir'//nl// &
            '  -c, --constants FILE  use the &constants of FILE (e.g. a best.nml from run)'//nl// &
            '  -q, --quiet           do not list the files written'//nl// &
            '  -h, --help            show this help'//nl// &
            '  -V, --version         show the version'
      case default
         text = 'usage: usharp simulate [options] <input.nml>'//nl//nl// &
            'Simulates every &test group of the input file with the &model and &constants'//nl// &
            'groups and writes one file <out_dir>/<test>.sim.txt per test.'//nl//nl// &
            'options:'//nl// &
            '  -o, --out-dir DIR     write to DIR instead of &output out_dir'//nl// &
            '  -c, --constants FILE  use the &constants of FILE (e.g. a best.nml from run)'//nl// &
            '  -t, --test NAME       simulate only the &test named NAME'//nl// &
            '  -q, --quiet           do not list the files written'//nl// &
            '  -h, --help            show this help'//nl// &
            '  -V, --version         show the version'
      end select
   end function command_usage
end program usharp_main
