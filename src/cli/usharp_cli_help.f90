!> The help texts of the program and its commands, and the version with the build
module usharp_cli_help
   use, intrinsic :: iso_c_binding, only: c_char, c_int, c_null_char
   use, intrinsic :: iso_fortran_env, only: compiler_version
   use omp_lib, only: openmp_version, omp_get_max_threads
   use usharp_version, only: usharp_version_string
   use usharp_strings, only: str
   use usharp_mpi, only: parallel_description
   implicit none
   private

   public :: main_help, command_help, version_text

   character(len=*), parameter :: nl = new_line('a')

   !> Exit codes, shown by every help text
   character(len=*), parameter :: exit_codes = &
      'exit codes: 0 success, 1 input error, 2 usage error, 3 failed simulation or fit,'//nl// &
      '            4 output not writable (disk full: no result file is left half written;'//nl// &
      '              standard output as well),'//nl// &
      '            5 fit done and written but its identifiability report failed,'//nl// &
      '            6 output folder in use by another run, 128+N stopped by signal N'//nl// &
      '            (143: SIGTERM, 130: Ctrl-C; continue with --resume)'

   !> Where the reference lives, shown by every command's help
   character(len=*), parameter :: see_docs = &
      'Input groups and variables: docs/reference/namelist.md; files written:'//nl// &
      'docs/reference/file-formats.md; a guide: docs/user-guide.md.'

   !> Options every command takes
   character(len=*), parameter :: common_options = &
      '  -o, --out-dir DIR     write to DIR instead of &output out_dir'//nl// &
      '  -h, --help            show this help'//nl// &
      '  -V, --version         show the version and the build'//nl// &
      '  --                    end of the options (for an input file named -x.nml)'

   !> --force of the commands that write over their own earlier output only
   character(len=*), parameter :: force_option = &
      '      --force           write over files of the names it writes that it did not'//nl// &
      '                        write itself (without it such a file is an error, exit 2)'//nl

   !> Options of the commands that keep a journal of their tasks
   character(len=*), parameter :: journal_options = &
      '      --resume          continue a stopped run from its journal (on any number of'//nl// &
      '                        ranks; refused when the input changed)'//nl// &
      '      --force           start again, overwriting the journal of an earlier run'//nl// &
      '      --auto-resume     --resume when the output folder holds a journal, else start'//nl

   interface
      function sundials_get_version(version, length) bind(C, name='SUNDIALSGetVersion') &
         result(flag)
         import :: c_char, c_int
         character(kind=c_char), intent(out) :: version(*)
         integer(c_int), value :: length
         integer(c_int) :: flag
      end function sundials_get_version
   end interface

contains

   !> The program's help: the commands and the options
   pure function main_help() result(text)
      character(len=:), allocatable :: text
      text = 'usage: usharp <command> [options] <input.nml>'//nl//nl// &
         'Determines the constants of a unified viscoplastic model (Miller, Chaboche) from'//nl// &
         'mechanical tests given in a namelist input file.'//nl//nl// &
         'commands:'//nl// &
         '  run        fit the constants of &fit to the data of every &test'//nl// &
         '  predict    apply a fit''s constants (-c best.nml) to other tests: errors, curves'//nl// &
         '  simulate   simulate every &test, write <out_dir>/<test>.sim.txt'//nl// &
         '  deck       write the ANSYS APDL input deck of a &test: <out_dir>/<test>.inp'//nl// &
         '  identify   identifiability of the &fit constants at the input''s constants'//nl// &
         '  design     rank candidate tests by how well they would determine the constants'//nl// &
         '  diagnose   where a fit falls short, which unmodelled effect explains it, how far'//nl// &
         '             adding it closes the gap (also on held-out tests)'//nl//nl// &
         '`usharp <command> --help` tells what a command reads and writes.'//nl//nl// &
         'options:'//nl// &
         '  -h, --help     show this help'//nl// &
         '  -V, --version  show the version and the build'//nl//nl// &
         exit_codes//nl//nl//'Documentation: docs/index.md'
   end function main_help

   !> A command's help: what it reads, what it writes, its options
   pure function command_help(command) result(text)
      !> the command
      character(len=*), intent(in) :: command
      character(len=:), allocatable :: text
      select case (command)
      case ('run')
         text = 'usage: usharp run [options] <fit.nml>'//nl//nl// &
            'Reads the &model, &constants (the start), &solver, &fit and &test groups and the'//nl// &
            'data files the tests name; fits the constants named in &fit. Writes into the'//nl// &
            'output folder GUESS.TXT, FOM.TXT, SUMS.TXT, fit.log, fit.journal, fit.cache,'//nl// &
            'best.nml, summary.txt, identify.txt and <test>.sim.txt / <test>.fit.txt per test.'//nl//nl// &
            'options:'//nl// &
            '  -c, --constants FILE  start from the &constants of FILE (e.g. a best.nml)'//nl// &
            '      --resume          continue a stopped run from its fit.journal (refused when'//nl// &
            '                        the input, constants or data files changed since)'//nl// &
            '      --force           start again, overwriting the fit.journal of an earlier run'//nl// &
            '                        (without --resume or --force such a journal is an error)'//nl// &
            '      --auto-resume     --resume when the output folder holds a journal, else a'//nl// &
            '                        fresh start (for job scripts: scripts/cluster)'//nl// &
            '  -q, --quiet           no progress line on stderr'//nl// &
            common_options
      case ('identify')
         text = 'usage: usharp identify [options] <fit.nml>'//nl//nl// &
            'Reads the input''s groups and data at its &constants (or those of --constants'//nl// &
            'FILE, e.g. a best.nml) and reports how well the tests determine the constants'//nl// &
            'named in &fit: singular values of the scaled Jacobian, 95 % intervals,'//nl// &
            'correlations, constants at a bound, poorly determined directions.'//nl// &
            'Writes <out_dir>/identify.txt.'//nl//nl// &
            'options:'//nl// &
            '  -c, --constants FILE  use the &constants of FILE (e.g. a best.nml from run)'//nl// &
            force_option// &
            '  -q, --quiet           no progress line on stderr'//nl// &
            common_options
      case ('design')
         text = 'usage: usharp design [options] <design.nml>'//nl//nl// &
            'Reads the &design group and the &test groups (current tests, and candidates with'//nl// &
            'candidate = .true.); simulates them with the known &constants (or those of'//nl// &
            '--constants FILE) and predicts, for a stress noise of &design noise, how well'//nl// &
            'each combination of up to max_tests tests determines the &fit constants.'//nl// &
            'Writes <out_dir>/design.txt and design.journal (every test''s information); a'//nl// &
            'design.txt it did not write is refused (exit 2) unless --force.'//nl// &
            'Under mpirun or srun the tests are spread over the ranks.'//nl//nl// &
            'options:'//nl// &
            '  -c, --constants FILE  use the &constants of FILE as the known constants'//nl// &
            journal_options// &
            '  -q, --quiet           no progress lines on stderr'//nl// &
            common_options
      case ('diagnose')
         text = 'usage: usharp diagnose [options] <fit.nml>'//nl// &
            '       usharp diagnose --selfcheck [options] [<selfcheck.nml>]'//nl//nl// &
            'Reads the fit''s input and the &diagnose group. Fits the tests not in &diagnose'//nl// &
            'holdout without any effect, splits the residual by test and region against the'//nl// &
            'noise level of the data, screens the catalogue of unmodelled effects, refits the'//nl// &
            'leading ones (AIC/BIC, 95 % intervals) and predicts the held-out tests with them.'//nl// &
            'Writes <out_dir>/diagnose/report.md, regions.csv, effects.csv, residuals.csv,'//nl// &
            'steps.csv (simulations and time of each step), plots and diagnose.journal'//nl// &
            '(each optimisation''s outcome: a diagnosis stopped by SIGTERM continues with'//nl// &
            '--resume to the same report; the per-specimen mode writes specimen-<name>.md'//nl// &
            'and .csv, kept in specimen.journal alike). With --selfcheck:'//nl// &
            'injects each effect into synthetic data (the built-in matrix, or the given'//nl// &
            'file), diagnoses it and writes <out_dir>/selfcheck.md and selfcheck.journal'//nl// &
            '(every repetition; under mpirun or srun spread over the ranks). A file of the'//nl// &
            'names it writes that it did not write is refused (exit 2) unless --force.'//nl// &
            'Guide: docs/guide/diagnosis.md.'//nl//nl// &
            'options:'//nl// &
            '  -c, --constants FILE  start from the &constants of FILE (e.g. a best.nml)'//nl// &
            '      --selfcheck       the self-check on synthetic data'//nl// &
            journal_options// &
            '  -q, --quiet           no progress lines on stderr'//nl// &
            common_options
      case ('deck')
         text = 'usage: usharp deck [options] [<test>] <input.nml>'//nl//nl// &
            'Reads the input''s groups; writes the ANSYS APDL input deck of the &test named'//nl// &
            '<test> (of every test when none is named) as <out_dir>/<test>.inp, and the'//nl// &
            'constants file it reads (the test''s constants_file, Constants.txt by default).'//nl// &
            'The deck needs an ANSYS linked with the usharp USERMAT: docs/guide/fe-users.md.'//nl//nl// &
            'options:'//nl// &
            '  -c, --constants FILE  use the &constants of FILE (e.g. a best.nml from run)'//nl// &
            force_option// &
            '  -q, --quiet           do not list the files written'//nl// &
            common_options
      case ('predict')
         text = 'usage: usharp predict -c best.nml [options] <input.nml>'//nl//nl// &
            'Reads the input''s &model, &solver, &output and &test groups (with their data files)'//nl// &
            'and the &constants of FILE (a best.nml of run: the fitted constants); simulates every test'//nl// &
            'and compares it with its data: RMS error, RMS error / peak of the data and largest'//nl// &
            'error per test. Writes <out_dir>/<test>.sim.txt, <test>.fit.txt (data beside the'//nl// &
            'prediction) and summary.txt (the table), as run does for the tests it fits.'//nl//nl// &
            'options:'//nl// &
            '  -c, --constants FILE  the fitted constants (required)'//nl// &
            force_option// &
            '  -q, --quiet           no progress line on stderr'//nl// &
            common_options
      case default
         text = 'usage: usharp simulate [options] <input.nml>'//nl//nl// &
            'Reads the &model, &constants, &solver and &test groups; simulates every test'//nl// &
            '(or one) and writes <out_dir>/<test>.sim.txt per test.'//nl//nl// &
            'options:'//nl// &
            '  -c, --constants FILE  use the &constants of FILE (e.g. a best.nml from run)'//nl// &
            '  -t, --test NAME       simulate only the &test named NAME'//nl// &
            force_option// &
            '  -q, --quiet           do not list the files written'//nl// &
            common_options
      end select
      text = text//nl//nl//see_docs//nl//nl//exit_codes
   end function command_help

   !> The version and what the program was built with
   function version_text() result(text)
      character(len=:), allocatable :: text
      character(kind=c_char) :: buffer(64)
      character(len=64) :: sundials, policy, threads_from
      integer :: i, status
      sundials = 'unknown'
      if (sundials_get_version(buffer, int(size(buffer), c_int)) == 0) then
         sundials = ''
         do i = 1, size(buffer)
            if (buffer(i) == c_null_char) exit
            sundials(i:i) = buffer(i)
         end do
      end if
      call get_environment_variable('OMP_WAIT_POLICY', policy, status=status)
      if (status /= 0) policy = 'runtime default'
      ! (where the count comes from: the variable, or the runtime's default, the processors)
      call get_environment_variable('OMP_NUM_THREADS', threads_from, status=status)
      threads_from = merge('OMP_NUM_THREADS ', 'runtime default ', status == 0)
      text = 'usharp '//usharp_version_string//nl// &
         'compiler: '//compiler_version()//nl// &
         'SUNDIALS: '//trim(sundials)//nl// &
         'OpenMP: '//str(openmp_version)//', '//str(omp_get_max_threads())// &
         ' thread'//trim(merge('s', ' ', omp_get_max_threads() /= 1))//' ('//trim(threads_from)// &
         '), wait policy '//trim(policy)//' (OMP_WAIT_POLICY)'//nl// &
         'MPI: '//parallel_description()
   end function version_text
end module usharp_cli_help
