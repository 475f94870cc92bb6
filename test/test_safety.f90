!> Tests of batch safety: a full disk, an earlier run's journal, two runs in one folder, a
!> changed input under --resume, a failed report after a fit, failing external commands, the
!> plot script and hostile folder names, what a resume costs, SIGTERM
module test_safety
   use, intrinsic :: iso_fortran_env, only: int32, int64
   use testdrive, only: error_type, unittest_type, new_unittest, check, test_failed, skip_test
   use usharp_kinds, only: dp
   use usharp_error, only: uerror => error_type, stat_io, stat_usage, stat_input, stat_busy, &
                           stat_failure, stat_report
   use usharp_filesys, only: raw_file, lock_file, unlock_file, join_path, absolute_path, &
                             file_exists, make_dir, hash_text, hash_hex, file_hash
   use usharp_output, only: write_lines
   use usharp_cmd_run, only: run_command
   use usharp_cmd_design, only: design_command
   use usharp_cmd_diagnose, only: diagnose_command
   use usharp_strings, only: str, report_line_len
   use usharp_cli_args, only: cli_command, arg_string, parse_arguments
   use test_util, only: write_text, usharp_exe, read_text, scratch_dir, check_message, fit_deck
   implicit none
   private
   public :: collect_safety

   character(len=*), parameter :: thesis = '../../data/thesis/'

contains

   subroutine collect_safety(testsuite)
      type(unittest_type), allocatable, intent(out) :: testsuite(:)
      testsuite = [ &
         new_unittest('fnv1a-hash-reference-values', test_hash), &
         new_unittest('writer-reports-a-full-device', test_dev_full), &
         new_unittest('disk-full-exit-4-no-half-file', test_disk_full), &
         new_unittest('standard-output-full-exit-4', test_stdout_full), &
         new_unittest('journal-kept-without-resume-or-force', test_journal_kept), &
         new_unittest('resume-of-a-finished-fit-keeps-its-cache', test_cache_kept), &
         new_unittest('specimen-reports-kept-without-force', test_specimen_kept), &
         new_unittest('specimen-diagnosis-resumed-same-reports', test_specimen_resume), &
         new_unittest('inputs-never-overwritten', test_inputs_kept), &
         new_unittest('user-files-and-fits-kept', test_strangers_kept), &
         new_unittest('user-files-kept-by-predict-identify-deck-simulate', test_own_files_kept), &
         new_unittest('user-files-kept-by-design-and-diagnose', test_reports_kept), &
         new_unittest('output-folder-locked-by-run-design-diagnose', test_lock), &
         new_unittest('resume-refused-after-a-change', test_fingerprint), &
         new_unittest('start-outside-its-bounds-told', test_start_outside), &
         new_unittest('torn-fingerprint-line-a-damaged-journal', test_torn_fingerprint), &
         new_unittest('fit-done-report-failed-exit-5', test_report_failed), &
         new_unittest('external-not-found-not-executable', test_external_127), &
         new_unittest('external-ignores-term-and-leaves-a-child', test_external_term), &
         new_unittest('plot-script-hostile-folder-name', test_plot_script), &
         new_unittest('lm-resume-at-90-percent-replays', test_resume_cost), &
         new_unittest('resumed-fit-log-names-every-penalty', test_resume_log), &
         new_unittest('damaged-fit-cache-resimulated-or-named', test_damaged_cache), &
         new_unittest('unwritable-cache-refused-journal-kept', test_unwritable_cache), &
         new_unittest('external-resume-reruns-no-journalled-command', test_external_resume), &
         new_unittest('sigterm-stops-with-a-note', test_sigterm)]
   end subroutine collect_safety

   !> A fit deck in the scratch folder: H1 and n of the thesis's LCF test by Hooke-Jeeves
   function deck(name, extra_fit, extra_test) result(path)
      character(len=*), intent(in) :: name, extra_fit, extra_test
      character(len=:), allocatable :: path, test
      test = "&test name='lcf', history='thesis_lcf', data_file='"//thesis//"lcf.sim.txt', "// &
             "weighting='threshold', sig=14 "//extra_test//" /"
      path = fit_deck(name, extra_fit, [test])
   end function deck

   !> Run a shell command line (the tests' own: fixed text and scratch paths), its exit status
   integer function shell(line) result(stat)
      character(len=*), intent(in) :: line
      call execute_command_line(line, exitstat=stat)
   end function shell

   subroutine test_hash(error)
      type(error_type), allocatable, intent(out) :: error
      ! FNV-1a 64 of '' and 'hello' (reference values of the algorithm)
      call check(error, hash_hex(hash_text('')) == 'CBF29CE484222325', hash_hex(hash_text('')))
      if (allocated(error)) return
      call check(error, hash_hex(hash_text('hello')) == 'A430D84680AABD0B', hash_hex(hash_text('hello')))
   end subroutine test_hash

   !> /dev/full refuses every write with ENOSPC, as a full disk does
   subroutine test_dev_full(error)
      type(error_type), allocatable, intent(out) :: error
      type(raw_file) :: f
      type(uerror), allocatable :: e
      if (.not. file_exists('/dev/full')) then
         call skip_test(error, '/dev/full does not exist here')
         return
      end if
      call f%create('/dev/full', e)
      if (.not. allocated(e)) call f%put('a line'//new_line('a'), e)
      call f%close()
      call check_message(error, e, '/dev/full: write failed (No space left on device)')
      if (allocated(error)) return
      call check(error, e%stat, stat_io, 'exit code 4')
   end subroutine test_dev_full

   !> What a command prints to a standard output that cannot take it (a full device, a closed
   !> descriptor) is not lost silently: exit 4, one line naming standard output
   subroutine test_stdout_full(error)
      type(error_type), allocatable, intent(out) :: error
      character(len=:), allocatable :: exe, errfile, input
      integer :: stat, k
      character(len=*), parameter :: into(2) = [character(len=10) :: '>/dev/full', '>&-']
      exe = usharp_exe()
      if (len(exe) == 0) then
         call skip_test(error, 'the usharp executable was not found beside the tester')
         return
      end if
      if (.not. file_exists('/dev/full')) then
         call skip_test(error, '/dev/full does not exist here')
         return
      end if
      errfile = scratch_dir//'/stdout-full.err'
      input = deck('stdout-full.nml', 'max_evals=6', '')
      do k = 1, size(into)
         stat = shell(exe//' --version '//trim(into(k))//' 2>'//errfile)
         call check(error, stat, 4, '--version '//trim(into(k))//': exit code')
         if (allocated(error)) return
         call check(error, index(read_text(errfile), 'usharp: error: standard output: write failed') == 1 &
                    .and. index(read_text(errfile), new_line('a')) == len(read_text(errfile)), &
                    'one line: '//read_text(errfile))
         if (allocated(error)) return
      end do
      ! (without --quiet: simulate names the files it wrote on standard output)
      stat = shell(exe//' simulate --force -o '//scratch_dir//'/stdout-full '//input// &
                   ' >/dev/full 2>'//errfile)
      call check(error, stat, 4, 'simulate >/dev/full: exit code')
      if (allocated(error)) return
      stat = shell(exe//' simulate --force -o '//scratch_dir//'/stdout-full '//input// &
                   ' >/dev/null 2>'//errfile)
      call check(error, stat, 0, 'simulate >/dev/null: exit code')
   end subroutine test_stdout_full

   !> run and simulate into a 64 KiB tmpfs: exit 4 naming the file; no result file is
   !> partial, no temporary file is left
   subroutine test_disk_full(error)
      type(error_type), allocatable, intent(out) :: error
      character(len=:), allocatable :: exe, mnt, errfile, text, input
      integer :: stat, k
      character(len=16), parameter :: results(6) = [character(len=16) :: 'best.nml', 'summary.txt', &
         'lcf.fit.txt', 'lcf.sim.txt', 'identify.txt', 'relax.sim.txt']
      exe = usharp_exe()
      if (len(exe) == 0) then
         call skip_test(error, 'the usharp executable was not found beside the tester')
         return
      end if
      mnt = scratch_dir//'/tiny'
      errfile = scratch_dir//'/tiny.err'
      stat = shell('umount '//mnt//' 2>/dev/null; mkdir -p '//mnt)
      stat = shell('mount -t tmpfs -o size=64k tmpfs '//mnt//' 2>/dev/null')
      if (stat /= 0) then
         call skip_test(error, 'cannot mount a 64 KiB tmpfs here (needs root and mount rights); '// &
                        'writer-reports-a-full-device covers the writer')
         return
      end if
      ! A fit whose logs fit and whose curves (35 kB each) do not
      input = deck('full.nml', 'max_evals=40', '')
      stat = shell(exe//' run -q '//input//' -o '//mnt//'/run > /dev/null 2> '//errfile)
      text = read_text(errfile)
      call check(error, stat, stat_io, 'run exit code: '//text)
      if (.not. allocated(error)) call check(error, index(text, 'write failed (No space left on device)') > 0 &
                                             .and. index(text, mnt//'/run/') > 0, 'message names the file: '//text)
      if (.not. allocated(error)) then
         do k = 1, size(results)
            call check(error, .not. file_exists(mnt//'/run/'//trim(results(k))//'.part'), &
                       'temporary file left: '//trim(results(k)))
            if (allocated(error)) exit
         end do
      end if
      if (.not. allocated(error)) then
         ! best.nml is written first: whole (it ends with the group's '/') or absent
         text = read_text(mnt//'/run/best.nml')
         call check(error, len(text) == 0 .or. index(text, new_line('a')//'/'//new_line('a')) > 0, &
                    'best.nml half written')
      end if
      if (.not. allocated(error)) then
         stat = shell('rm -rf '//mnt//'/run; '//exe//' simulate -q decks/thesis-data.nml -o '//mnt// &
                      '/sim > /dev/null 2> '//errfile)
         text = read_text(errfile)
         call check(error, stat, stat_io, 'simulate exit code: '//text)
         if (.not. allocated(error)) call check(error, index(text, '.sim.txt: write failed') > 0, text)
         if (.not. allocated(error)) call check(error, .not. file_exists(mnt//'/sim/ratchet.sim.txt.part') .and. &
                                                .not. file_exists(mnt//'/sim/relax.sim.txt.part'), 'temporary file left')
      end if
      stat = shell('umount '//mnt)
   end subroutine test_disk_full

   !> --resume of a fit that has finished replays it and leaves fit.cache as the fit wrote
   !> it, byte for byte (the last start's residual vectors; it had been cut to its header)
   subroutine test_cache_kept(error)
      use usharp_filesys, only: file_hash
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: e
      character(len=report_line_len), allocatable :: summary(:)
      character(len=:), allocatable :: input, dir
      integer(int64) :: h1, h2
      logical :: ok1, ok2
      input = deck('cache-kept.nml', "method='lm', max_evals=40", '')
      dir = scratch_dir//'/cache-kept'
      call run_command(input, dir, '', .false., summary, e, force=.true.)
      if (allocated(e)) then
         call test_failed(error, 'first run: '//e%message)
         return
      end if
      call file_hash(dir//'/fit.cache', h1, ok1)
      call run_command(input, dir, '', .true., summary, e)
      if (allocated(e)) then
         call test_failed(error, 'resume: '//e%message)
         return
      end if
      call file_hash(dir//'/fit.cache', h2, ok2)
      call check(error, ok1 .and. ok2 .and. h1 == h2 .and. file_size(dir//'/fit.cache') > 16, &
                 'fit.cache changed by the resume of a finished fit')
   contains
      integer function file_size(path) result(n)
         character(len=*), intent(in) :: path
         inquire (file=path, size=n)
      end function file_size
   end subroutine test_cache_kept

   !> A second run into a folder with a journal is refused, naming --resume and --force
   subroutine test_journal_kept(error)
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: e
      character(len=report_line_len), allocatable :: summary(:)
      character(len=:), allocatable :: input, dir, journal
      type(cli_command) :: cmd
      input = deck('journal.nml', 'max_evals=12', '')
      dir = scratch_dir//'/journal-out'
      call run_command(input, dir, '', .false., summary, e, force=.true.)
      if (allocated(e)) then
         call test_failed(error, 'first run: '//e%message)
         return
      end if
      journal = read_text(dir//'/fit.journal')
      call run_command(input, dir, '', .false., summary, e)
      call check_message(error, e, 'holds the journal of an earlier run; continue it with --resume, '// &
                         'or start again and overwrite it with --force')
      if (allocated(error)) return
      call check(error, e%stat, stat_usage, 'exit code 2')
      if (allocated(error)) return
      call check(error, read_text(dir//'/fit.journal') == journal, 'the journal is untouched')
      if (allocated(error)) return
      call run_command(input, dir, '', .false., summary, e, force=.true.)
      call check(error, .not. allocated(e), '--force starts again')
      if (allocated(error)) return
      ! On the command line: --force is an option of run; with --resume a usage error
      call parse_arguments([arg_string('run'), arg_string('--force'), arg_string('f.nml')], cmd, e)
      call check(error, .not. allocated(e) .and. cmd%force, 'run --force parsed')
      if (allocated(error)) return
      call refused('--resume', '--resume continues the journal, --force overwrites it: give one')
      if (allocated(error)) return
      call refused('--auto-resume', '--auto-resume continues a journal it finds, --force overwrites it: give one')
   contains
      !> run with option and --force: a usage error with this message, exit code 2
      subroutine refused(option, message)
         character(len=*), intent(in) :: option, message
         call parse_arguments([arg_string('run'), arg_string(option), arg_string('--force'), &
                               arg_string('f.nml')], cmd, e)
         call check_message(error, e, message)
         if (allocated(error)) return
         call check(error, e%stat, stat_usage, 'exit code 2')
      end subroutine refused
   end subroutine test_journal_kept

   !> A per-specimen diagnosis into a folder that holds a report of an earlier one, or a file
   !> of the user's of its name, is refused before any work, the file kept, naming --force
   !> (as a run's journal is)
   subroutine test_specimen_kept(error)
      use usharp_cmd_diagnose, only: diagnose_command
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: e
      character(len=report_line_len), allocatable :: summary(:)
      character(len=:), allocatable :: input, dir, mine, notes
      input = fit_deck('specimen-kept.nml', '', [character(len=200) :: &
         "&test name='lcf', history='thesis_lcf', data_file='"//thesis//"lcf.sim.txt', weighting='threshold', sig=14 /", &
         "&test name='relax', history='relaxation', data_file='"//thesis//"relax.sim.txt', weighting='relaxation' /", &
         "&diagnose specimen = 'lcf' /"])
      dir = scratch_dir//'/specimen-kept-out'
      call check(error, shell('rm -rf '//dir//'; mkdir -p '//dir//'/diagnose') == 0, 'clean folder')
      if (allocated(error)) return
      mine = write_text('specimen-kept-out/diagnose/specimen-lcf.md', [character(len=20) :: 'my notes'])
      notes = read_text(mine)
      call check(error, index(notes, 'my notes') == 1, 'the report to keep was not written: '//mine)
      if (allocated(error)) return
      call diagnose_command(input, dir, '', summary, e)
      call check_message(error, e, 'specimen-lcf.md: a file of this name is there that usharp diagnose '// &
                         'did not write; overwrite it with --force')
      if (allocated(error)) return
      call check(error, e%stat, stat_usage, 'exit code 2')
      if (allocated(error)) return
      call check(error, read_text(mine) == notes, 'the notes are untouched')
      if (allocated(error)) return
      ! A report of an earlier run (known by its first line) is kept alike
      mine = write_text('specimen-kept-out/diagnose/specimen-lcf.md', [character(len=40) :: &
         '# Per-specimen diagnosis: lcf', 'earlier findings'])
      notes = read_text(mine)
      call diagnose_command(input, dir, '', summary, e)
      call check_message(error, e, 'specimen-lcf.md: holds the report of an earlier run; start again and '// &
                         'overwrite it with --force')
      if (allocated(error)) return
      call check(error, e%stat, stat_usage, 'exit code 2')
      if (allocated(error)) return
      call check(error, read_text(mine) == notes, 'the report is untouched')
   end subroutine test_specimen_kept

   !> A per-specimen diagnosis keeps each specimen's report and table in
   !> diagnose/specimen.journal: a run resumed (or resumed by --auto-resume) replays them into
   !> the same files; the table has a row per parameter of each effect, as the report has
   subroutine test_specimen_resume(error)
      use usharp_cmd_diagnose, only: diagnose_command
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: e
      character(len=report_line_len), allocatable :: first(:), again(:)
      character(len=:), allocatable :: input, dir, lcf, relax, table
      integer :: k
      input = fit_deck('specimen-resume.nml', '', [character(len=200) :: &
         "&test name='lcf', history='thesis_lcf', data_file='"//thesis//"lcf.sim.txt', weighting='threshold', sig=14 /", &
         "&test name='relax', history='relaxation', data_file='"//thesis//"relax.sim.txt', weighting='relaxation' /", &
         "&diagnose specimen = 'all', effects = 'temperature', 'drift', global_starts = 2 /"])
      dir = scratch_dir//'/specimen-resume-out'
      call check(error, shell('rm -rf '//dir) == 0, 'clean folder')
      if (allocated(error)) return
      call diagnose_command(input, dir, '', first, e)
      if (allocated(e)) then
         call test_failed(error, e%message)
         return
      end if
      lcf = read_text(dir//'/diagnose/specimen-lcf.md')
      relax = read_text(dir//'/diagnose/specimen-relax.md')
      call check(error, file_exists(dir//'/diagnose/specimen.journal') .and. len(lcf) > 0 .and. len(relax) > 0, &
                 'reports and journal written')
      if (allocated(error)) return
      ! temperature (dT) and drift (the specimen's d): a row each after the header; the
      ! summary says what it wrote
      table = read_text(dir//'/diagnose/specimen-lcf.csv')
      call check(error, index(table, 'specimen,rank,effect,parameters,') == 1 .and. &
                 count([(table(k:k) == new_line('a'), k=1, len(table))]) == 3 .and. &
                 index(table, new_line('a')//'lcf,1,') > 0 .and. index(table, new_line('a')//'lcf,2,') > 0 .and. &
                 index(table, ',dT,') > 0 .and. index(table, ',K,') > 0 .and. index(table, ',d,') > 0 .and. &
                 index(table, ',1/s,') > 0, 'the table of effects: '//table)
      if (allocated(error)) return
      call check(error, any(index(first, 'wrote '//dir//'/diagnose/specimen-lcf.md, specimen-lcf.csv') == 1), &
                 'no line names the files written')
      if (allocated(error)) return
      ! A setting of the held-out diagnosis is said to do nothing here
      call check(error, index(first(1), '&diagnose: global_starts: not used by the per-specimen mode') > 0, &
                 'no note of the unused setting: '//trim(first(1)))
      if (allocated(error)) return
      call diagnose_command(input, dir, '', again, e, mode='resume')
      if (allocated(e)) then
         call test_failed(error, 'resume: '//e%message)
         return
      end if
      call check(error, all(first == again) .and. read_text(dir//'/diagnose/specimen-lcf.md') == lcf .and. &
                 read_text(dir//'/diagnose/specimen-relax.md') == relax .and. &
                 read_text(dir//'/diagnose/specimen-lcf.csv') == table, 'the resumed reports are the same')
      if (allocated(error)) return
      call diagnose_command(input, dir, '', again, e, mode='auto')
      call check(error, .not. allocated(e), '--auto-resume of a finished per-specimen diagnosis')
      if (allocated(error)) return
      call diagnose_command(input, dir, '', again, e)
      call check_message(error, e, 'specimen.journal')
   end subroutine test_specimen_resume

   !> A run into a folder that holds a summary.txt no run made (no journal) is refused, the
   !> file kept, unless --force; a prediction, a simulation or an identification into a fit's
   !> folder is refused, the fit's files kept
   subroutine test_strangers_kept(error)
      use usharp_cmd_predict, only: predict_command
      use usharp_cmd_simulate, only: simulate_command
      use usharp_cmd_identify, only: identify_command
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: e
      character(len=report_line_len), allocatable :: summary(:)
      character(len=4096), allocatable :: written(:)
      character(len=:), allocatable :: input, dir, fit_summary, fit_curve
      character(len=*), parameter :: own(10) = [character(len=12) :: 'best.nml', 'summary.txt', &
         'identify.txt', 'GUESS.TXT', 'FOM.TXT', 'SUMS.TXT', 'fit.log', 'fit.cache', 'lcf.sim.txt', &
         'lcf.fit.txt']
      integer :: k
      input = deck('strangers.nml', 'max_evals=12', '')
      dir = scratch_dir//'/strangers-out'
      ! A folder of its own, as a user's: no journal from an earlier run of this test
      call check(error, shell('rm -rf '//dir) == 0, 'clean folder')
      if (allocated(error)) return
      call make_dir(dir, e)
      call write_lines(dir//'/summary.txt', [character(len=20) :: 'my notes'], e)
      call run_command(input, dir, '', .false., summary, e)
      call check_message(error, e, 'summary.txt: a file of this name is there, and no '// &
                         'fit.journal says a run made it')
      if (allocated(error)) return
      call check(error, e%stat, stat_usage, 'exit code 2')
      if (allocated(error)) return
      call check(error, read_text(dir//'/summary.txt') == 'my notes'//new_line('a'), 'the notes are kept')
      if (allocated(error)) return
      ! --auto-resume with no journal to continue starts afresh, and keeps out as a run does
      call run_command(input, dir, '', .false., summary, e, auto_resume=.true.)
      call check_message(error, e, 'summary.txt: a file of this name is there, and no '// &
                         'fit.journal says a run made it')
      if (allocated(error)) return
      call check(error, read_text(dir//'/summary.txt') == 'my notes'//new_line('a'), &
                 'the notes are kept by --auto-resume')
      if (allocated(error)) return
      ! Every name a run writes is refused alike (identify.txt had been cut to 11 characters)
      do k = 1, size(own)
         call check(error, shell('rm -rf '//dir//'-one') == 0, 'clean folder')
         if (allocated(error)) return
         call make_dir(dir//'-one', e)
         call write_lines(dir//'-one/'//trim(own(k)), [character(len=20) :: 'my notes'], e)
         call run_command(input, dir//'-one', '', .false., summary, e)
         call check_message(error, e, trim(own(k))//': a file of this name is there')
         if (allocated(error)) return
         call check(error, read_text(dir//'-one/'//trim(own(k))) == 'my notes'//new_line('a'), &
                    trim(own(k))//' is kept')
         if (allocated(error)) return
      end do
      call run_command(input, dir, '', .false., summary, e, force=.true.)
      call check(error, .not. allocated(e), '--force overwrites them')
      if (allocated(error)) return
      fit_summary = read_text(dir//'/summary.txt')
      call predict_command(input, dir, dir//'/best.nml', summary, e)
      call check_message(error, e, 'holds a fit (fit.journal)')
      if (allocated(error)) return
      call check(error, read_text(dir//'/summary.txt') == fit_summary, "the fit's summary is kept")
      if (allocated(error)) return
      ! Nor do simulate and identify write over the fit's curves and report
      fit_curve = read_text(dir//'/lcf.sim.txt')
      call simulate_command(input, dir, written, e)
      call check_message(error, e, 'whose lcf.sim.txt simulate would replace')
      if (allocated(error)) return
      call check(error, e%stat, stat_usage, 'simulate: exit code 2')
      if (allocated(error)) return
      call check(error, read_text(dir//'/lcf.sim.txt') == fit_curve, "the fit's curve is kept")
      if (allocated(error)) return
      call identify_command(input, dir, '', summary, e)
      call check_message(error, e, 'whose identify.txt identify would replace')
      if (allocated(error)) return
      ! The user guide's workflow: simulate, then fit into the same folder; the curves that
      ! simulate wrote are usharp's, and the fit replaces them
      call check(error, shell('rm -rf '//dir//'-sim') == 0, 'clean folder')
      if (allocated(error)) return
      call simulate_command(input, dir//'-sim', written, e)
      call check(error, .not. allocated(e), 'simulate into a new folder')
      if (allocated(error)) return
      call run_command(input, dir//'-sim', '', .false., summary, e)
      call check(error, .not. allocated(e), 'a run after simulate into the same folder')
      if (allocated(error)) return
      ! A fit still running has its journal and no curves yet: simulate keeps out all the same
      call check(error, shell('rm -rf '//dir//'-run && mkdir -p '//dir//'-run && cp '//dir// &
                 '/fit.journal '//dir//'-run/') == 0, 'a folder with a journal alone')
      if (allocated(error)) return
      call simulate_command(input, dir//'-run', written, e)
      call check_message(error, e, 'holds a fit (fit.journal), which writes lcf.sim.txt at its end')
   end subroutine test_strangers_kept

   !> predict, identify and deck into a folder with no fit that holds a user's file of a name
   !> they write are refused before writing anything, naming the file and --force, the file
   !> kept; --force writes over it, and each command run again over its own earlier output
   !> (or predict over the curves of simulate) needs no --force
   subroutine test_own_files_kept(error)
      use usharp_cmd_predict, only: predict_command
      use usharp_cmd_identify, only: identify_command
      use usharp_cmd_deck, only: deck_command
      use usharp_cmd_simulate, only: simulate_command
      use usharp_overwrite, only: begins_like, simulate_mark
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: e
      character(len=report_line_len), allocatable :: summary(:)
      character(len=4096), allocatable :: written(:)
      character(len=:), allocatable :: input, dir
      type(cli_command) :: cmd
      character(len=*), parameter :: commands(4) = [character(len=8) :: 'predict', 'identify', 'deck', &
         'simulate']
      character(len=*), parameter :: names(7) = [character(len=13) :: 'summary.txt', 'lcf.sim.txt', &
         'lcf.fit.txt', 'identify.txt', 'lcf.inp', 'Constants.txt', 'lcf.sim.txt']
      character(len=*), parameter :: writer(7) = [character(len=8) :: 'predict', 'predict', &
         'predict', 'identify', 'deck', 'deck', 'simulate']
      integer :: k
      ! usharp's own first lines are told by a pattern, '*' standing for the version
      call check(error, begins_like("# usharp 0.1.0 simulation of test 'lcf' (history", simulate_mark//"lcf'") &
                 .and. .not. begins_like("# usharp 0.1.0 simulation of test 'lcf2'", simulate_mark//"lcf'") &
                 .and. .not. begins_like("x # usharp 0.1.0 simulation of test 'lcf'", simulate_mark) &
                 .and. .not. begins_like("# usharp simulation of test 'lcf'", simulate_mark), 'begins_like')
      if (allocated(error)) return
      ! The deck's own constants serve as the fitted ones for predict
      input = deck('own-files.nml', 'max_evals=12', '')
      dir = scratch_dir//'/own-files-out'
      do k = 1, size(names)
         call refused(trim(writer(k)), trim(names(k)))
         if (allocated(error)) return
         call run(trim(writer(k)), .true.)
         call check(error, .not. allocated(e), trim(writer(k))//' --force writes over '//trim(names(k)))
         if (allocated(error)) return
         call check(error, read_text(dir//'/'//trim(names(k))) /= 'my notes'//new_line('a'), &
                    trim(names(k))//' is written over with --force')
         if (allocated(error)) return
         call run(trim(writer(k)), .false.)
         call check(error, .not. allocated(e), trim(writer(k))//' again over its own files')
         if (allocated(error)) return
      end do
      ! A user's file under the temporary name a result is written through is refused as
      ! well, and kept; --force writes the result over it (and renames it into place)
      call check(error, shell('rm -rf '//dir//' && mkdir -p '//dir) == 0, 'clean folder')
      if (allocated(error)) return
      call write_lines(dir//'/lcf.fit.txt.part', [character(len=20) :: 'my notes'], e)
      call run('predict', .false.)
      call check_message(error, e, dir//'/lcf.fit.txt.part: a file of this name is there, '// &
                         'which usharp predict would write lcf.fit.txt through')
      if (allocated(error)) return
      call check(error, e%stat, stat_usage, 'predict over lcf.fit.txt.part: exit code 2')
      if (allocated(error)) return
      call check(error, read_text(dir//'/lcf.fit.txt.part') == 'my notes'//new_line('a'), &
                 'lcf.fit.txt.part is kept')
      if (allocated(error)) return
      call run('predict', .true.)
      call check(error, .not. allocated(e) .and. .not. file_exists(dir//'/lcf.fit.txt.part'), &
                 'predict --force over lcf.fit.txt.part')
      if (allocated(error)) return
      ! Files of one command are another's strangers: a deck's files are not a prediction's
      call run('deck', .false.)
      call check(error, shell('mv '//dir//'/lcf.inp '//dir//'/lcf.sim.txt') == 0, 'a deck renamed')
      if (allocated(error)) return
      call run('predict', .false.)
      call check_message(error, e, 'lcf.sim.txt: a file of this name is there that usharp predict')
      if (allocated(error)) return
      ! predict after simulate into the same folder: simulate's curves are usharp's look at
      ! the model, which the prediction replaces (as a fit does)
      call check(error, shell('rm -rf '//dir) == 0, 'clean folder')
      if (allocated(error)) return
      call simulate_command(input, dir, written, e)
      call check(error, .not. allocated(e), 'simulate into a new folder')
      if (allocated(error)) return
      call run('predict', .false.)
      call check(error, .not. allocated(e), 'predict after simulate into the same folder')
      if (allocated(error)) return
      ! A folder of an output name cannot be written over even with --force: the reason is
      ! told (it had been left out)
      call check(error, shell('rm -rf '//dir//' && mkdir -p '//dir//'/lcf.sim.txt') == 0, 'a folder lcf.sim.txt')
      if (allocated(error)) return
      call simulate_command(input, dir, written, e, force=.true.)
      call check_message(error, e, 'lcf.sim.txt: cannot move the finished file into place')
      if (allocated(error)) return
      call check(error, index(e%message, '(Is a directory)') > 0, 'the reason: '//e%message)
      if (allocated(error)) return
      ! The command that made a curve is given in its header as one can paste it: a folder
      ! name with a blank in quotes
      call simulate_command(input, dir//'/a b', written, e)
      call check(error, .not. allocated(e), 'simulate into a folder with a blank')
      if (allocated(error)) return
      call check(error, index(read_text(dir//'/a b/lcf.sim.txt'), "--out-dir '"//dir//"/a b'") > 0, &
                 'the folder quoted in the regenerate line')
      if (allocated(error)) return
      ! On the command line --force is an option of each of them
      do k = 1, size(commands)
         call parse_arguments([arg_string(trim(commands(k))), arg_string('--force'), arg_string('-c'), &
                               arg_string('b.nml'), arg_string('f.nml')], cmd, e)
         call check(error, .not. allocated(e) .and. cmd%force, trim(commands(k))//' --force parsed')
         if (allocated(error)) return
      end do
   contains
      !> The command into a folder that holds the user's file name alone: refused, the file
      !> kept
      subroutine refused(command, name)
         character(len=*), intent(in) :: command, name
         call check(error, shell('rm -rf '//dir//' && mkdir -p '//dir) == 0, 'clean folder')
         if (allocated(error)) return
         call write_lines(dir//'/'//name, [character(len=20) :: 'my notes'], e)
         call run(command, .false.)
         call check_message(error, e, dir//'/'//name//': a file of this name is there that usharp '// &
                            command//' did not write; overwrite it with --force')
         if (allocated(error)) return
         call check(error, e%stat, stat_usage, command//' over '//name//': exit code 2')
         if (allocated(error)) return
         call check(error, read_text(dir//'/'//name) == 'my notes'//new_line('a'), name//' is kept')
         if (allocated(error)) return
         call check(error, shell('test $(ls '//dir//' | wc -l) -eq 1') == 0, &
                    command//' wrote nothing beside '//name)
      end subroutine refused
      subroutine run(command, force)
         character(len=*), intent(in) :: command
         logical, intent(in) :: force
         select case (command)
         case ('predict')
            call predict_command(input, dir, input, summary, e, force)
         case ('identify')
            call identify_command(input, dir, '', summary, e, force)
         case ('simulate')
            call simulate_command(input, dir, written, e, force=force)
         case default
            call deck_command(input, '', dir, '', written, e, force)
         end select
      end subroutine run
   end subroutine test_own_files_kept

   !> design and diagnose (held-out, per specimen, self-check) into a folder that holds a
   !> user's file of a name they write are refused before any work, naming the file and
   !> --force, the file kept; --force writes over it, and --resume over their own reports
   subroutine test_reports_kept(error)
      use usharp_cmd_diagnose, only: diagnose_command, selfcheck_command
      use usharp_diagnose_report, only: report_names
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: e
      character(len=report_line_len), allocatable :: summary(:)
      character(len=:), allocatable :: input, dir
      integer :: k
      input = fit_deck('reports-kept.nml', "method='lm'", [character(len=200) :: &
         "&test name='lcf', history='thesis_lcf', data_file='"//thesis//"lcf.sim.txt', weighting='threshold', sig=14 /", &
         "&test name='relax', history='relaxation', data_file='"//thesis//"relax.sim.txt', "// &
         "weighting='relaxation', candidate=.true. /", &
         "&diagnose holdout = 'relax', effects = 'lag', n_refit = 1 /"])
      dir = scratch_dir//'/reports-kept-out'
      do k = 1, size(report_names)
         call refused('diagnose/'//trim(report_names(k)), 'diagnose')
         if (allocated(error)) return
         call check(error, .not. file_exists(dir//'/diagnose/diagnose.journal'), &
                    'diagnose refused over '//trim(report_names(k))//' after it began its journal')
         if (allocated(error)) return
      end do
      call diagnose_command(input, dir, '', summary, e, mode='force')
      call check(error, .not. allocated(e), 'diagnose --force writes over the user''s file')
      if (allocated(error)) return
      call diagnose_command(input, dir, '', summary, e, mode='resume')
      call check(error, .not. allocated(e), 'diagnose --resume over its own reports')
      if (allocated(error)) return
      ! A user's image of a plot's name is a PNG as usharp's are: known by the hash that
      ! plots.gp records of usharp's, it is refused and kept
      call check(error, shell("printf '\211PNG\r\n\032\nmine' > "//dir//'/diagnose/fit.png') == 0, &
                 'a user''s PNG')
      if (allocated(error)) return
      call diagnose_command(input, dir, '', summary, e, mode='resume')
      call check_message(error, e, dir//'/diagnose/fit.png: a file of this name is there that usharp '// &
                         'diagnose did not write; overwrite it with --force')
      if (allocated(error)) return
      call check(error, index(read_text(dir//'/diagnose/fit.png'), 'mine') > 0, 'the user''s PNG is kept')
      if (allocated(error)) return
      call refused('design.txt', 'design')
      if (allocated(error)) return
      call design_command(input, dir, '', summary, e, 'force')
      call check(error, .not. allocated(e), 'design --force writes over the user''s file')
      if (allocated(error)) return
      call check(error, read_text(dir//'/design.txt') /= 'my notes'//new_line('a'), 'design.txt written')
      if (allocated(error)) return
      call design_command(input, dir, '', summary, e, 'resume')
      call check(error, .not. allocated(e), 'design --resume over its own report')
      if (allocated(error)) return
      call refused('selfcheck.md', 'diagnose')
   contains
      !> The command into a folder that holds the user's file name alone: refused, the file
      !> kept
      subroutine refused(name, command)
         character(len=*), intent(in) :: name, command
         call check(error, shell('rm -rf '//dir//' && mkdir -p '//dir//'/diagnose') == 0, 'clean folder')
         if (allocated(error)) return
         call write_lines(dir//'/'//name, [character(len=20) :: 'my notes'], e)
         select case (name)
         case ('design.txt')
            call design_command(input, dir, '', summary, e, 'start')
         case ('selfcheck.md')
            call selfcheck_command('', dir, summary, e, 'start')
         case default
            call diagnose_command(input, dir, '', summary, e)
         end select
         call check_message(error, e, dir//'/'//name//': a file of this name is there that usharp '// &
                            command//' did not write; overwrite it with --force')
         if (allocated(error)) return
         call check(error, e%stat, stat_usage, command//' over '//name//': exit code 2')
         if (allocated(error)) return
         call check(error, read_text(dir//'/'//name) == 'my notes'//new_line('a'), name//' is kept')
      end subroutine refused
   end subroutine test_reports_kept

   !> No run writes over its own inputs, --force or not: the constants given with -c that are
   !> the output folder's best.nml, and a test 'lcf' whose data are lcf.sim.txt in the output
   !> folder, are refused with an input error that names them, and stay as they were; so too
   !> by simulate (which with -t minds only that test's curve) and deck (its input deck)
   subroutine test_inputs_kept(error)
      use usharp_cmd_simulate, only: simulate_command
      use usharp_cmd_deck, only: deck_command
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: e
      character(len=report_line_len), allocatable :: summary(:)
      character(len=4096), allocatable :: written(:)
      character(len=:), allocatable :: input, dir, best, data
      character(len=*), parameter :: deck_inputs(2) = [character(len=13) :: 'lcf.inp', 'Constants.txt']
      integer :: k
      input = deck('kept.nml', 'max_evals=12', '')
      dir = scratch_dir//'/kept-out'
      call run_command(input, dir, '', .false., summary, e, force=.true.)
      if (allocated(e)) then
         call test_failed(error, 'first run: '//e%message)
         return
      end if
      best = read_text(dir//'/best.nml')
      call run_command(input, dir, dir//'/best.nml', .false., summary, e, force=.true.)
      call check_message(error, e, 'an input of this run, and '//dir//'/best.nml is a file it writes')
      if (allocated(error)) return
      call check(error, e%stat, stat_input, 'exit code 1')
      if (allocated(error)) return
      call check(error, read_text(dir//'/best.nml') == best, 'the constants file is untouched')
      if (allocated(error)) return
      ! The data in the output folder under the name of the test's simulation
      call make_dir(scratch_dir//'/kept-data', e)
      call check(error, shell('cp '//thesis(7:)//'lcf.sim.txt '//scratch_dir//'/kept-data/') == 0, &
                 'copy of the data')
      if (allocated(error)) return
      data = read_text(scratch_dir//'/kept-data/lcf.sim.txt')
      input = write_text('kept-data/kept.nml', [character(len=400) :: &
         "&model name='miller', units='ksi', temperature=866.15, tm=1800.0, youngs=22.5e3 /", &
         '&constants a1=0.8, a2=7.42e-5, b=1e15, c2=0.1, h1=200, h2=100, n=5.0, q=91000 /', &
         "&fit fitted='H1','n', max_evals=12 /", &
         "&test name='lcf', history='thesis_lcf', data_file='lcf.sim.txt', weighting='threshold', sig=14 /"])
      call run_command(input, scratch_dir//'/kept-data', '', .false., summary, e, force=.true.)
      call check_message(error, e, 'lcf.sim.txt: an input of this run')
      if (allocated(error)) return
      call check(error, read_text(scratch_dir//'/kept-data/lcf.sim.txt') == data, 'the data are untouched')
      if (allocated(error)) return
      ! simulate -t writes only that test's curve: another test's data of a simulate name
      ! there is no obstacle (and without -t it is)
      input = write_text('kept-data/kept2.nml', [character(len=400) :: &
         "&model name='miller', units='ksi', temperature=866.15, tm=1800.0, youngs=22.5e3 /", &
         '&constants a1=0.8, a2=7.42e-5, b=1e15, c2=0.1, h1=200, h2=100, n=5.0, q=91000 /', &
         "&test name='lcf', history='thesis_lcf', data_file='lcf.sim.txt', weighting='threshold', sig=14 /", &
         "&test name='relax', history='relaxation', levels=0.00075, ramp_time=1.0, holds=60.0, "// &
         "dt_out=5.0 /"])
      call simulate_command(input, scratch_dir//'/kept-data', written, e, only_test='relax', force=.true.)
      call check(error, .not. allocated(e), 'simulate -t relax beside the data of lcf')
      if (allocated(error)) return
      call simulate_command(input, scratch_dir//'/kept-data', written, e, force=.true.)
      call check_message(error, e, 'lcf.sim.txt: an input of this run')
      if (allocated(error)) return
      call check(error, read_text(scratch_dir//'/kept-data/lcf.sim.txt') == data, &
                 'the data are untouched by simulate')
      if (allocated(error)) return
      ! Nor a load history read from a file (history 'file') of a name simulate writes
      input = write_text('kept-data/kept3.nml', [character(len=400) :: &
         "&model name='miller', units='ksi', temperature=866.15, tm=1800.0, youngs=22.5e3 /", &
         '&constants a1=0.8, a2=7.42e-5, b=1e15, c2=0.1, h1=200, h2=100, n=5.0, q=91000 /', &
         "&test name='lcf', history='file', file='lcf.sim.txt' /"])
      call simulate_command(input, scratch_dir//'/kept-data', written, e, force=.true.)
      call check_message(error, e, 'lcf.sim.txt: an input of this run')
      if (allocated(error)) return
      call check(error, read_text(scratch_dir//'/kept-data/lcf.sim.txt') == data, &
                 'the load history is untouched by simulate --force')
      if (allocated(error)) return
      ! Nor does deck --force write over the input deck, named as a deck or as the constants
      ! file it writes
      do k = 1, 2
         call check(error, shell('cp '//scratch_dir//'/kept-data/kept2.nml '//scratch_dir// &
                    '/kept-data/'//trim(deck_inputs(k))) == 0, 'copy of the deck')
         if (allocated(error)) return
         call deck_command(scratch_dir//'/kept-data/'//trim(deck_inputs(k)), 'lcf', &
                           scratch_dir//'/kept-data', '', written, e, .true.)
         call check_message(error, e, trim(deck_inputs(k))//': an input of this run')
         if (allocated(error)) return
         call check(error, read_text(scratch_dir//'/kept-data/'//trim(deck_inputs(k))) == &
                    read_text(scratch_dir//'/kept-data/kept2.nml'), trim(deck_inputs(k))//' is untouched')
         if (allocated(error)) return
      end do
   end subroutine test_inputs_kept

   !> While another process holds the folder's lock a run exits 6; the lock file left behind
   !> by a run is no lock
   subroutine test_lock(error)
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: e
      character(len=report_line_len), allocatable :: summary(:), lines(:)
      character(len=:), allocatable :: input, dir
      integer :: fd
      input = deck('lock.nml', 'max_evals=6', '')
      dir = scratch_dir//'/lock-out'
      call make_dir(dir, e)
      ! flock locks of two open files conflict even within one process
      call lock_file(dir//'/.usharp.lock', fd, e)
      call check(error, fd >= 0, 'the test takes the lock')
      if (allocated(error)) return
      call run_command(input, dir, '', .false., summary, e, force=.true.)
      call unlock_file(fd)
      call check_message(error, e, 'another usharp is writing into this folder')
      if (allocated(error)) return
      call check(error, e%stat, stat_busy, 'exit code 6')
      if (allocated(error)) return
      ! A design and a diagnosis hold their folders alike (two into one had shared a journal)
      call make_dir(dir//'/diagnose', e)
      call lock_file(dir//'/diagnose/.usharp.lock', fd, e)
      call diagnose_command('decks/thesis-diagnose.nml', dir, '', lines, e, mode='force')
      call unlock_file(fd)
      call check_message(error, e, 'another usharp is writing into this folder')
      if (allocated(error)) return
      call check(error, e%stat, stat_busy, 'diagnose: exit code 6')
      if (allocated(error)) return
      call lock_file(dir//'/.usharp.lock', fd, e)
      call design_command('decks/thesis-design.nml', dir, '', lines, e, 'force')
      call unlock_file(fd)
      call check_message(error, e, 'another usharp is writing into this folder')
      if (allocated(error)) return
      call check(error, e%stat, stat_busy, 'design: exit code 6')
      if (allocated(error)) return
      call check(error, file_exists(dir//'/.usharp.lock'), 'lock file present')
      if (allocated(error)) return
      call run_command(input, dir, '', .false., summary, e, force=.true.)
      call check(error, .not. allocated(e), 'run after the lock is released')
   end subroutine test_lock

   !> A bounded search from a start outside its bounds begins at the bound: the summary says so
   !> beside the start it shows
   subroutine test_start_outside(error)
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: e
      character(len=report_line_len), allocatable :: summary(:)
      character(len=:), allocatable :: input
      integer :: k
      logical :: told
      input = deck('start-outside.nml', "method='lm', max_evals=6, identify=.false., upper=150.0, 8.0", '')
      call run_command(input, scratch_dir//'/start-outside-out', '', .false., summary, e, force=.true.)
      if (allocated(e)) then
         call test_failed(error, e%message)
         return
      end if
      told = .false.
      do k = 1, size(summary)
         if (index(summary(k), 'H1') > 0 .and. index(summary(k), '(above its upper bound 1.500E+02: '// &
                                                      'searched from it)') > 0) told = .true.
      end do
      call check(error, told, 'H1 = 200 above its upper bound 150 not told in the summary')
   end subroutine test_start_outside

   !> --resume refuses when a data file, a peak file, the input or the constants file changed
   !> (given then and not now included), before it writes anything
   subroutine test_fingerprint(error)
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: e
      character(len=report_line_len), allocatable :: summary(:)
      character(len=:), allocatable :: input, dir, data, hist, journal, peaks
      character(len=4000) :: edited(1)
      integer :: stat
      dir = scratch_dir//'/fingerprint-out'
      data = scratch_dir//'/fingerprint-lcf.txt'
      stat = shell('cp data/thesis/lcf.sim.txt '//data)
      input = write_text('fingerprint.nml', [character(len=4000) :: &
         "&model name='miller', units='ksi', temperature=866.15, tm=1800.0, youngs=22.5e3 /", &
         '&constants a1=0.8, a2=7.42e-5, b=1e15, c2=0.1, h1=200, h2=100, n=5.0, q=91000 /', &
         "&fit fitted='H1','n', rho=0.5, eps=1e-4, itermax=200, max_evals=10 /", &
         "&test name='lcf', history='thesis_lcf', data_file='fingerprint-lcf.txt', "// &
         "weighting='threshold', sig=14 /"])
      call run_command(input, dir, '', .false., summary, e, force=.true.)
      if (allocated(e)) then
         call test_failed(error, 'first run: '//e%message)
         return
      end if
      call run_command(input, dir, '', .true., summary, e)
      call check(error, .not. allocated(e), 'resume of an unchanged fit')
      if (allocated(error)) return
      ! The data changed (a comment line is enough)
      stat = shell('echo "# changed" >> '//data)
      call run_command(input, dir, '', .true., summary, e)
      call check_message(error, e, "cannot resume: the data file of test 'lcf' changed since the journal was written")
      if (allocated(error)) return
      call check(error, e%stat, stat_input, 'exit code 1')
      if (allocated(error)) return
      ! The input changed too
      edited(1) = read_text(input)//'! edited'
      input = write_text('fingerprint.nml', edited)
      call run_command(input, dir, '', .true., summary, e)
      call check_message(error, e, "cannot resume: the input file, the data file of test 'lcf' changed")
      if (allocated(error)) return
      ! A constants file given with -c is part of the fingerprint
      call run_command(input, dir, 'decks/thesis-run2.nml', .true., summary, e)
      call check_message(error, e, 'the constants file (--constants)')
      if (allocated(error)) return
      ! A history file: its contents reach the fit through the control history
      hist = write_text('fingerprint-hist.csv', [character(len=20) :: '0 0', '120 0.005', '240 0'])
      input = write_text('fingerprint-hist.nml', [character(len=4000) :: &
         "&model name='miller', units='ksi', temperature=866.15, tm=1800.0, youngs=22.5e3 /", &
         '&constants a1=0.8, a2=7.42e-5, b=1e15, c2=0.1, h1=200, h2=100, n=5.0, q=91000 /', &
         "&fit fitted='H1','n', max_evals=5, identify=.false. /", &
         "&test name='h', history='file', file='fingerprint-hist.csv', data_file='"//thesis// &
         "lcf.sim.txt' /"])
      call run_command(input, dir, '', .false., summary, e, force=.true.)
      if (allocated(e)) then
         call test_failed(error, 'run on a history file: '//e%message)
         return
      end if
      hist = write_text('fingerprint-hist.csv', [character(len=20) :: '0 0', '120 0.006', '240 0'])
      call run_command(input, dir, '', .true., summary, e)
      call check_message(error, e, "cannot resume: the control history of test 'h' changed")
      if (allocated(error)) return
      ! A run made with -c and resumed without it is refused before anything is written:
      ! the journal keeps its records, and the resume with -c goes on
      call run_command(input, dir, 'decks/thesis-run2.nml', .false., summary, e, force=.true.)
      if (allocated(e)) then
         call test_failed(error, 'run with -c: '//e%message)
         return
      end if
      journal = read_text(dir//'/fit.journal')
      call run_command(input, dir, '', .true., summary, e)
      call check_message(error, e, 'the constants file (--constants), given then and not now, changed')
      if (allocated(error)) return
      call check(error, read_text(dir//'/fit.journal') == journal, 'the refused resume leaves the journal')
      if (allocated(error)) return
      call run_command(input, dir, 'decks/thesis-run2.nml', .true., summary, e)
      call check(error, .not. allocated(e), 'the resume with -c')
      if (allocated(error)) return
      ! A peak file (target 'peaks') is read by the fit as a data file is
      peaks = write_text('fingerprint-peaks.csv', [character(len=40) :: 'cycle,time_max,max,time_min,min', &
         '1,5.0,31.5,15.0,-30.5', '2,25.0,32.0,35.0,-31.0', '3,45.0,32.5,55.0,-31.5'])
      input = write_text('fingerprint-peaks.nml', [character(len=4000) :: &
         "&model name='miller', units='ksi', temperature=866.15, tm=1800.0, youngs=22.5e3 /", &
         '&constants a1=0.8, a2=7.42e-5, b=1e15, c2=0.1, h1=200, h2=100, n=5.0, q=91000 /', &
         "&fit fitted='H1','n', max_evals=5, identify=.false. /", &
         "&test name='c', history='cyclic', strain_range=0.01, strain_rate=1e-3, cycles=3, "// &
         "target='peaks', peak_file='fingerprint-peaks.csv' /"])
      call run_command(input, dir, '', .false., summary, e, force=.true.)
      if (allocated(e)) then
         call test_failed(error, 'run on a peak file: '//e%message)
         return
      end if
      peaks = write_text('fingerprint-peaks.csv', [character(len=40) :: 'cycle,time_max,max,time_min,min', &
         '1,5.0,47.3,15.0,-45.8', '2,25.0,48.0,35.0,-46.5', '3,45.0,48.8,55.0,-47.3'])
      call run_command(input, dir, '', .true., summary, e)
      call check_message(error, e, "cannot resume: the peak file of test 'c' changed")
      if (allocated(error)) return
      ! The journal of another build of the program (its build hash replaced)
      call run_command(input, dir, '', .false., summary, e, force=.true.)
      call check(error, .not. allocated(e), 'run on the changed peak file')
      if (allocated(error)) return
      stat = shell("sed -i '1s/ build=[0-9A-Fa-z]* / build=0123456789ABCDEF /' "//dir//'/fit.journal')
      call check(error, index(read_text(dir//'/fit.journal'), ' build=0123456789ABCDEF ') > 0, &
                 'the journal names no build: '//read_text(dir//'/fit.journal'))
      if (allocated(error)) return
      call run_command(input, dir, '', .true., summary, e)
      call check_message(error, e, 'cannot resume: the program (another build of usharp) changed since '// &
                         'the journal was written')
   end subroutine test_fingerprint

   !> A journal whose fingerprint line is cut short (within an item, at an item's end without
   !> its line end, or a whole line with a hash cut short) is reported as a damaged journal,
   !> naming it and --force, not as data files that changed; a design journal alike
   subroutine test_torn_fingerprint(error)
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: e
      character(len=report_line_len), allocatable :: summary(:)
      character(len=:), allocatable :: input, dir, head
      character(len=*), parameter :: damaged = &
         '/fit.journal: cannot resume: the journal is damaged (its fingerprint line is cut short); '// &
         'start again with --force'
      integer :: stat
      input = deck('torn-fingerprint.nml', "max_evals=10, identify=.false.", '')
      dir = scratch_dir//'/torn-fingerprint-out'
      call run_command(input, dir, '', .false., summary, e, force=.true.)
      if (allocated(e)) then
         call test_failed(error, 'first run: '//e%message)
         return
      end if
      stat = shell('cp '//dir//'/fit.journal '//dir//'.whole')
      head = read_text(dir//'.whole')
      head = head(:index(head, new_line('a')) - 1)
      ! Cut within the data file's hash, as `truncate -s 100` does
      call resume_cut('truncate -s 100 '//dir//'/fit.journal')
      if (allocated(error)) return
      ! Cut at the end of an item, without the line's end
      call resume_cut('head -c '//str(index(head, ' data:') - 1)//' '//dir//'.whole > '//dir//'/fit.journal')
      if (allocated(error)) return
      ! A whole line with a hash cut short, the records after it
      call resume_cut('{ head -c '//str(index(head, ' data:') - 3)//' '//dir//'.whole; echo; tail -n +2 '// &
                      dir//'.whole; } > '//dir//'/fit.journal')
      if (allocated(error)) return
      ! The journal of design, through the task farm
      dir = scratch_dir//'/torn-fingerprint-design'
      stat = shell('rm -rf '//dir)
      input = deck('torn-fingerprint-design.nml', '', ', candidate=.true.')
      call design_command(input, dir, '', summary, e, 'start')
      if (allocated(e)) then
         call test_failed(error, 'design: '//e%message)
         return
      end if
      stat = shell('truncate -s 60 '//dir//'/design.journal')
      call design_command(input, dir, '', summary, e, 'resume')
      call check_message(error, e, dir//'/design.journal: cannot resume: the journal is damaged')
   contains
      !> The journal damaged by a shell command, then --resume: refused as damaged
      subroutine resume_cut(command)
         character(len=*), intent(in) :: command
         call check(error, shell(command) == 0, command)
         if (allocated(error)) return
         call run_command(input, dir, '', .true., summary, e)
         call check_message(error, e, dir//damaged)
         if (allocated(error)) return
         call check(error, e%stat, stat_input, 'exit code 1 after: '//command)
      end subroutine resume_cut
   end subroutine test_torn_fingerprint

   !> A fit whose identifiability report fails: results written, warning in summary.txt and
   !> identify.txt, exit code 5. The report's simulations fail here because the stand-in FE
   !> command refuses the report's work folders.
   subroutine test_report_failed(error)
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: e
      character(len=report_line_len), allocatable :: summary(:)
      character(len=:), allocatable :: exe, input, dir, ext
      exe = usharp_exe()
      if (len(exe) == 0) then
         call skip_test(error, 'the usharp executable was not found beside the tester')
         return
      end if
      dir = scratch_dir//'/report-out'
      ext = ", backend='external', constants_format='(ES24.16)', command='case {work} in "// &
            "*identify*) echo no report here >&2; exit 9;; esac; sh "//absolute_path('test/ansys_standin.sh')// &
            ' '//absolute_path(exe)//" {input_dir}/report-internal.nml {test}'"
      input = write_text('report-internal.nml', [character(len=4000) :: &
         "&model name='miller', units='ksi', temperature=866.15, tm=1800.0, youngs=22.5e3 /", &
         '&constants a1=0.8, a2=7.42e-5, b=1e15, c2=0.1, h1=200, h2=100, n=5.0, q=91000 /', &
         "&fit fitted='H1','n' /", &
         "&test name='lcf', history='thesis_lcf', data_file='"//thesis//"lcf.sim.txt' /"])
      input = deck('report.nml', 'max_evals=3, identify=.true.', ext)
      call run_command(input, dir, '', .false., summary, e, force=.true.)
      call check_message(error, e, 'the fit is done and written, but its identifiability report failed')
      if (allocated(error)) return
      call check(error, e%stat, stat_report, 'exit code 5')
      if (allocated(error)) return
      call check(error, index(read_text(dir//'/best.nml'), '&constants') > 0, 'best.nml written')
      if (allocated(error)) return
      call check(error, index(read_text(dir//'/summary.txt'), 'warning: the identifiability report failed') > 0 &
                 .and. index(read_text(dir//'/summary.txt'), 'test lcf:') > 0, 'summary.txt: fit and warning')
      if (allocated(error)) return
      call check(error, index(read_text(dir//'/identify.txt'), 'warning: the identifiability report failed') > 0, &
                 'identify.txt: warning')
   end subroutine test_report_failed

   !> A command not found (127) or not executable (126) is a failed evaluation with its
   !> reason; when it fails everywhere the run ends as a failed fit (exit 3), as with the
   !> internal integrator
   subroutine test_external_127(error)
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: e
      character(len=report_line_len), allocatable :: summary(:)
      character(len=:), allocatable :: input, dir, script
      integer :: stat
      dir = scratch_dir//'/ext127-out'
      input = deck('ext127.nml', 'max_evals=2, identify=.false.', &
                   ", backend='external', command='no-such-fe-program {constants}'")
      call run_command(input, dir, '', .false., summary, e, force=.true.)
      call check_message(error, e, 'command not found (exit status 127)')
      if (allocated(error)) return
      call check(error, e%stat, stat_failure, 'exit code 3')
      if (allocated(error)) return
      call check(error, index(read_text(dir//'/fit.log'), 'evaluation 1: penalty') > 0, &
                 'a failed evaluation in fit.log')
      if (allocated(error)) return
      script = scratch_dir//'/not-executable.sh'
      stat = shell('echo "exit 0" > '//script//'; chmod -x '//script)
      input = deck('ext126.nml', 'max_evals=2, identify=.false.', &
                   ", backend='external', command='"//absolute_path(script)//"'")
      call run_command(input, dir, '', .false., summary, e, force=.true.)
      call check_message(error, e, 'command not executable (exit status 126)')
      if (allocated(error)) return
      call check(error, e%stat, stat_failure, 'exit code 3')
   end subroutine test_external_127

   !> A command that ignores TERM is stopped at its time limit (KILL after the grace
   !> period) and reported as such; a background child it leaves goes with its group
   subroutine test_external_term(error)
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: e
      character(len=report_line_len), allocatable :: summary(:)
      character(len=:), allocatable :: input, dir, pid
      integer :: stat
      dir = scratch_dir//'/extterm-out'
      stat = shell('rm -rf '//dir)
      input = deck('extterm.nml', 'max_evals=1, identify=.false.', &
                   ", backend='external', time_limit=0.5, command='sleep 60 & echo $! > ../child.pid; "// &
                   "trap """" TERM; sleep 60'")
      call run_command(input, dir, '', .false., summary, e, force=.true.)
      call check_message(error, e, 'command ran past its time_limit of 0.500000 s and was stopped')
      if (allocated(error)) return
      pid = trim(read_text(dir//'/work/child.pid'))
      if (len(pid) > 0) pid = pid(:len(pid) - 1)
      call check(error, len(pid) > 0, 'the background child wrote its pid')
      if (allocated(error)) return
      ! Gone, or a zombie waiting for a parent that does not reap
      stat = shell('test ! -e /proc/'//pid//' || grep -q ") Z" /proc/'//pid//'/stat')
      call check(error, stat, 0, 'the background child '//pid//' is still running')
   end subroutine test_external_term

   !> scripts/plot-fit.sh with a folder name that would be gnuplot code if pasted into it
   subroutine test_plot_script(error)
      type(error_type), allocatable, intent(out) :: error
      character(len=:), allocatable :: dir
      integer :: stat
      if (shell('command -v gnuplot > /dev/null 2>&1') /= 0) then
         call skip_test(error, 'gnuplot is not installed')
         return
      end if
      dir = scratch_dir//'/plot/p";system("touch pwned");print "'
      stat = shell("rm -rf "//scratch_dir//"/plot pwned; mkdir -p '"//dir//"' && "// &
                   "cp data/thesis/lcf.sim.txt '"//dir//"/a"" b.fit.txt'")
      call check(error, stat, 0, 'scratch folder with a hostile name')
      if (allocated(error)) return
      stat = shell("cd "//scratch_dir//"/plot && bash ../../../scripts/plot-fit.sh '"// &
                   'p";system("touch pwned");print "'//"' 'x""; system(""touch pwned""); y' > /dev/null 2>&1")
      call check(error, stat, 0, 'plot-fit.sh exit status')
      if (allocated(error)) return
      call check(error, .not. file_exists(scratch_dir//'/plot/pwned') .and. .not. file_exists('pwned'), &
                 'a command in the folder name or title ran')
      if (allocated(error)) return
      call check(error, file_exists(dir//'/plots/a" b.png') .and. file_exists(dir//'/plots/all.png'), &
                 'plots written')
      if (allocated(error)) return
      ! A run started again with fewer tests: the file of the test it no longer has stays in
      ! the folder, and only the tests its summary.txt names are plotted
      dir = scratch_dir//'/plot/again'
      stat = shell('mkdir -p '//dir//' && cp data/thesis/lcf.sim.txt '//dir//'/lcf.fit.txt && '// &
                   'cp data/thesis/lcf.sim.txt '//dir//'/gone.fit.txt && printf "%s\n" '// &
                   '"usharp run x.nml: best of 1 start" "  objective (eq7): start 1, best 1" '// &
                   '"  test lcf: 1.0E+00" > '//dir//'/summary.txt && '// &
                   'bash scripts/plot-fit.sh '//dir//' > /dev/null 2>&1')
      call check(error, stat, 0, 'plot-fit.sh exit status, a test gone')
      if (allocated(error)) return
      call check(error, file_exists(dir//'/plots/lcf.png') .and. .not. file_exists(dir//'/plots/gone.png'), &
                 'only the test of the run''s summary.txt plotted')
   end subroutine test_plot_script

   !> Levenberg-Marquardt from 2 starts, stopped after 90 % of its evaluations (in its second
   !> start) and resumed: the resumed run simulates at most 15 % of the evaluations and ends bit
   !> for bit as the uninterrupted one; without its fit.cache it simulates only the second
   !> start's evaluations again (the journal closes the first), and counts them not replayed;
   !> with the line closing the first start torn, it simulates both starts again, and with
   !> that line's optimum damaged the first start
   subroutine test_resume_cost(error)
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: e
      character(len=report_line_len), allocatable :: summary(:)
      character(len=:), allocatable :: input, full, part, cut
      integer :: ntotal, nkept, nrep, nsim, stat, m, k1
      input = deck('lmresume.nml', "method='lm', multistart=2, seed=3, identify=.false.", &
                   ", dt_out=4.0")
      full = scratch_dir//'/lmresume-full'
      part = scratch_dir//'/lmresume-part'
      call uninterrupted_run(input, full, summary, error)
      if (allocated(error)) return
      call counts(summary(3), ntotal, nrep, nsim)
      call check(error, ntotal > 40 .and. nsim == ntotal, 'uninterrupted run: '//trim(summary(3)))
      if (allocated(error)) return
      ! The first start's last evaluation, from the line that closes it in the journal
      k1 = closing_evaluation(full//'/fit.journal', 1)
      nkept = (9*ntotal)/10
      call check(error, k1 > 0 .and. k1 < nkept, 'the first start does not end before 90 % of '// &
                 'the evaluations: '//str(k1)//' of '//str(ntotal))
      if (allocated(error)) return
      ! The journal and the cache as a kill after 90 % of the evaluations leaves them: the
      ! journal's lines up to its nkept-th record; fit.cache holds the second start only (each
      ! start begins it anew): its header (16 bytes) and the second start's records up to
      ! nkept, each of 4 + 4 bytes, 2 constants and m residuals
      m = residual_count(full//'/fit.cache', ntotal - k1)
      cut = 'awk -v n='//str(nkept)//' ''!/^#/ { k++ } k > n { exit } { print }'' '//full//'/fit.journal > '// &
            part//'/fit.journal'
      stat = shell('rm -rf '//part//'; mkdir -p '//part//' && '//cut//' && head -c '// &
                   str(16 + (nkept - k1)*(8 + 8*(2 + m)))//' '//full//'/fit.cache > '//part//'/fit.cache')
      call resumed('resumed at 90 %', nkept, 0, (15*ntotal)/100)
      if (allocated(error)) return
      ! Without fit.cache the journal gives no residual vector of the second start: its
      ! evaluations are simulated again, and the summary counts only the first start's replayed
      stat = shell('rm -rf '//part//'; mkdir -p '//part//' && '//cut)
      call resumed('resumed without fit.cache', k1, ntotal - k1, ntotal - k1)
      if (allocated(error)) return
      ! The line closing the first start torn by a kill (its reason cut short) closes nothing:
      ! the first start's search is replayed, here simulated again (no cache), to the same end
      stat = shell('rm -rf '//part//'; mkdir -p '//part//' && awk ''/^# start-done 1 / { printf "%s", '// &
                   'substr($0, 1, length($0) - 3); exit } { print }'' '//full//'/fit.journal > '//part//'/fit.journal')
      call resumed('resumed after a torn start-done line', 0, ntotal, ntotal)
      if (allocated(error)) return
      ! Its optimum damaged (the first digit of f): none of the start's evaluations, so it
      ! closes nothing either; the second start's line still closes it
      stat = shell('rm -rf '//part//'; mkdir -p '//part//' && awk ''/^# start-done 1 / { $10 = "9" '// &
                   'substr($10, 2) } { print }'' '//full//'/fit.journal > '//part//'/fit.journal')
      call resumed('resumed after a damaged start-done line', ntotal - k1, k1, k1)
   contains
      !> Resume the run in part: nrep evaluations replayed, nsim_lo to nsim_hi simulated, and
      !> the journal and best.nml of the uninterrupted run
      subroutine resumed(what, nrep_want, nsim_lo, nsim_hi)
         character(len=*), intent(in) :: what
         integer, intent(in) :: nrep_want, nsim_lo, nsim_hi
         call run_command(input, part, '', .true., summary, e)
         if (allocated(e)) then
            call test_failed(error, what//': '//e%message)
            return
         end if
         call counts(summary(3), ntotal, nrep, nsim)
         call check(error, nrep == nrep_want .and. nsim_lo <= nsim .and. nsim <= nsim_hi, &
                    what//': '//trim(summary(3)))
         if (allocated(error)) return
         call check(error, read_text(part//'/fit.journal') == read_text(full//'/fit.journal'), &
                    what//': journal not identical')
         if (allocated(error)) return
         call check(error, body(read_text(part//'/best.nml')) == body(read_text(full//'/best.nml')), &
                    what//': best.nml not identical')
      end subroutine resumed
   end subroutine test_resume_cost

   !> fit.log of a Hooke-Jeeves fit resumed half-way names every penalised evaluation with
   !> its reason, as the uninterrupted run's does (it is written anew as the journal replays)
   subroutine test_resume_log(error)
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: e
      character(len=report_line_len), allocatable :: summary(:)
      character(len=:), allocatable :: full, part
      integer :: stat
      full = scratch_dir//'/penalty-full'
      part = scratch_dir//'/penalty-part'
      call run_command('decks/thesis-run2.nml', full, '', .false., summary, e, force=.true.)
      if (allocated(e)) then
         call test_failed(error, 'uninterrupted run: '//e%message)
         return
      end if
      stat = shell('rm -rf '//part//'; mkdir -p '//part//' && head -n 500 '//full//'/fit.journal > '// &
                   part//'/fit.journal && cp '//full//'/fit.log '//part//'/')
      call run_command('decks/thesis-run2.nml', part, '', .true., summary, e)
      if (allocated(e)) then
         call test_failed(error, 'resumed run: '//e%message)
         return
      end if
      call check(error, shell('grep "^evaluation " '//full//'/fit.log > '//full//'/penalties && '// &
                 'grep "^evaluation " '//part//'/fit.log > '//part//'/penalties && cmp -s '//full// &
                 '/penalties '//part//'/penalties && grep -q "^evaluation 14: penalty 2.000E+10: '// &
                 'constant A1 must be" '//part//'/penalties'), 0, &
                 'the penalised evaluations in the resumed fit.log')
   end subroutine test_resume_log

   !> A resume where fit.cache cannot be written (a folder of that name with a file in it):
   !> refused with exit 4 naming the file, before the journal is started anew, so that the
   !> journal is as it was and resumes once the folder is gone
   subroutine test_unwritable_cache(error)
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: e
      character(len=report_line_len), allocatable :: summary(:)
      character(len=:), allocatable :: input, dir, journal
      integer :: stat
      input = deck('unwritable-cache.nml', "method='lm', identify=.false.", ", dt_out=4.0")
      dir = scratch_dir//'/unwritable-cache'
      call uninterrupted_run(input, dir, summary, error)
      if (allocated(error)) return
      journal = read_text(dir//'/fit.journal')
      stat = shell('rm -f '//dir//'/fit.cache && mkdir -p '//dir//'/fit.cache/kept')
      call run_command(input, dir, '', .true., summary, e)
      call check_message(error, e, dir//'/fit.cache: cannot write')
      if (allocated(error)) return
      call check(error, e%stat, stat_io, 'exit code 4')
      if (allocated(error)) return
      call check(error, read_text(dir//'/fit.journal') == journal, 'the journal changed')
      if (allocated(error)) return
      stat = shell('rm -rf '//dir//'/fit.cache')
      call run_command(input, dir, '', .true., summary, e)
      call check(error, .not. allocated(e), 'resume after the folder is gone failed')
      if (allocated(error)) return
      call check(error, read_text(dir//'/fit.journal') == journal, 'the resumed journal differs')
   end subroutine test_unwritable_cache

   !> A fit.cache with damaged bytes: a residual vector that does not give its evaluation's
   !> objective is simulated again (the resumed journal is the uninterrupted one); a damaged
   !> sensitivity Jacobian, which nothing checks, stops the resume with an input error that
   !> names fit.cache, not the journal
   subroutine test_damaged_cache(error)
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: e
      character(len=report_line_len), allocatable :: summary(:)
      character(len=:), allocatable :: input, full, part, journal
      integer :: stat
      integer(int64) :: h0, h1
      logical :: ok, ok1
      input = deck('damaged-cache.nml', "method='lm', jacobian='sensitivity', identify=.false.", &
                   ", dt_out=4.0")
      full = scratch_dir//'/damaged-cache-full'
      part = scratch_dir//'/damaged-cache-part'
      call uninterrupted_run(input, full, summary, error)
      if (allocated(error)) return
      call check(error, line_count(full//'/fit.journal') > 12, 'too few evaluations to resume')
      if (allocated(error)) return
      call copy_part()
      call damage(part//'/fit.cache', 1, 5)
      call run_command(input, part, '', .true., summary, e)
      if (allocated(e)) then
         call test_failed(error, 'resumed over a damaged residual vector: '//e%message)
         return
      end if
      call check(error, read_text(part//'/fit.journal') == read_text(full//'/fit.journal'), &
                 'journal identical after a damaged residual vector')
      if (allocated(error)) return
      call copy_part()
      call damage(part//'/fit.cache', 2, 2)
      journal = read_text(part//'/fit.journal')
      call file_hash(part//'/fit.cache', h0, ok)
      call run_command(input, part, '', .true., summary, e)
      call check_message(error, e, part//'/fit.cache: cannot resume: the residuals or Jacobians '// &
                         'replayed from this file led the search off fit.journal at evaluation')
      if (allocated(error)) return
      call check(error, e%stat, stat_input, 'exit code 1')
      if (allocated(error)) return
      ! Refused before the logs are started anew: the journal and the cache as they were
      call file_hash(part//'/fit.cache', h1, ok1)
      call check(error, read_text(part//'/fit.journal') == journal .and. ok .and. ok1 .and. h0 == h1, &
                 'the refused resume leaves journal and cache')
   contains
      !> The journal's first 12 records and the whole cache, as a kill leaves them
      subroutine copy_part()
         stat = shell('rm -rf '//part//'; mkdir -p '//part//' && head -n 13 '//full// &
                      '/fit.journal > '//part//'/fit.journal && cp '//full//'/fit.cache '//part//'/')
      end subroutine copy_part
   end subroutine test_damaged_cache

   !> Overwrite a value of the nth record of kind (1 residuals, 2 Jacobian) in fit.cache at
   !> path, past its point x: 'USHARPC1', m, n; then records of kind, index, x, values
   subroutine damage(path, kind, nth)
      character(len=*), intent(in) :: path
      integer, intent(in) :: kind, nth
      character(len=8) :: magic
      integer(int32) :: m, n, rk, idx
      integer(int64) :: pos
      integer :: unit, seen
      open (newunit=unit, file=path, access='stream', form='unformatted', status='old', action='readwrite')
      read (unit) magic, m, n
      pos = 17
      seen = 0
      do
         read (unit, pos=pos) rk, idx
         if (rk == kind) seen = seen + 1
         if (seen == nth) then
            write (unit, pos=pos + 8 + 8*n + 8*min(m - 1, 40)) 12345.678_dp
            exit
         end if
         pos = pos + 8 + 8*n + 8*merge(m, m*n, rk == 1)
      end do
      close (unit)
   end subroutine damage

   !> An external Levenberg-Marquardt fit resumed at 90 %: the FE command runs again only for
   !> evaluations the journal does not hold (and once for the best fit's curves)
   subroutine test_external_resume(error)
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: e
      character(len=report_line_len), allocatable :: summary(:)
      character(len=:), allocatable :: exe, input, full, part, count, ext
      integer :: ntotal, nrep, nsim, nkept, m, stat, nruns
      exe = usharp_exe()
      if (len(exe) == 0) then
         call skip_test(error, 'the usharp executable was not found beside the tester')
         return
      end if
      count = absolute_path(scratch_dir)//'/extresume-count.txt'
      input = write_text('extresume-internal.nml', [character(len=4000) :: &
         "&model name='miller', units='ksi', temperature=866.15, tm=1800.0, youngs=22.5e3 /", &
         '&constants a1=0.8, a2=7.42e-5, b=1e15, c2=0.1, h1=200, h2=100, n=5.0, q=91000 /', &
         "&test name='lcf', history='thesis_lcf', data_file='"//thesis//"lcf.sim.txt', dt_out=4.0 /"])
      ext = ", dt_out=4.0, backend='external', constants_format='(ES24.16)', command='echo run >> "// &
            count//"; sh "//absolute_path('test/ansys_standin.sh')//' '//absolute_path(exe)// &
            " {input_dir}/extresume-internal.nml {test}'"
      input = deck('extresume.nml', "method='lm', max_evals=24, identify=.false.", ext)
      full = scratch_dir//'/extresume-full'
      part = scratch_dir//'/extresume-part'
      stat = shell('rm -f '//count)
      call uninterrupted_run(input, full, summary, error)
      if (allocated(error)) return
      call counts(summary(3), ntotal, nrep, nsim)
      nruns = line_count(count)
      call check(error, ntotal > 10 .and. nruns == ntotal + 1, 'uninterrupted run: '//str(nruns)// &
                 ' command runs; '//trim(summary(3)))
      if (allocated(error)) return
      nkept = (9*ntotal)/10
      m = residual_count(full//'/fit.cache', ntotal)
      stat = shell('rm -rf '//part//' '//count//'; mkdir -p '//part//' && head -n '//str(nkept + 1)//' '// &
                   full//'/fit.journal > '//part//'/fit.journal && head -c '//str(16 + nkept*(8 + 8*(2 + m)))// &
                   ' '//full//'/fit.cache > '//part//'/fit.cache')
      call run_command(input, part, '', .true., summary, e)
      if (allocated(e)) then
         call test_failed(error, 'resumed run: '//e%message)
         return
      end if
      nruns = line_count(count)
      call check(error, nruns == ntotal - nkept + 1, 'resumed at evaluation '//str(nkept)//' of '// &
                 str(ntotal)//': the command ran '//str(nruns)//' times')
      if (allocated(error)) return
      call check(error, read_text(part//'/fit.journal') == read_text(full//'/fit.journal'), 'journal identical')
   end subroutine test_external_resume

   !> The number of lines of the file at path (0 if it cannot be read)
   integer function line_count(path) result(k)
      character(len=*), intent(in) :: path
      integer :: unit, ios
      character(len=16) :: line
      k = 0
      open (newunit=unit, file=path, status='old', action='read', iostat=ios)
      if (ios /= 0) return
      do
         read (unit, '(a)', iostat=ios) line
         if (ios /= 0) exit
         k = k + 1
      end do
      close (unit)
   end function line_count

   !> Evaluations, replayed and simulated from the summary's line
   subroutine counts(line, n, nr, ns)
      character(len=*), intent(in) :: line
      integer, intent(out) :: n, nr, ns
      integer :: k, ios
      character(len=32) :: w(6)
      k = index(line, 'evaluations')
      read (line(k:), *, iostat=ios) w
      n = -1
      nr = -1
      ns = -1
      if (ios /= 0) return
      read (w(2), *, iostat=ios) n
      read (w(3)(2:), *, iostat=ios) nr
      read (w(5), *, iostat=ios) ns
   end subroutine counts

   !> The last evaluation of start s, from the line of the journal at path that closes it
   !> ('# start-done s first last ...'; 0 if there is none)
   integer function closing_evaluation(path, s) result(last)
      character(len=*), intent(in) :: path
      integer, intent(in) :: s
      character(len=4096) :: line
      integer :: unit, ios, start, first
      last = 0
      open (newunit=unit, file=path, status='old', action='read', iostat=ios)
      if (ios /= 0) return
      do
         read (unit, '(a)', iostat=ios) line
         if (ios /= 0) exit
         if (index(line, '# start-done ') /= 1) cycle
         read (line(14:), *, iostat=ios) start, first, last
         if (ios == 0 .and. start == s) exit
         last = 0
      end do
      close (unit)
   end function closing_evaluation

   !> Residuals per record of a fit.cache of nrec residual records and 2 constants
   integer function residual_count(path, nrec) result(mm)
      character(len=*), intent(in) :: path
      integer, intent(in) :: nrec
      integer :: unit
      integer(8) :: bytes
      open (newunit=unit, file=path, access='stream', form='unformatted', status='old', action='read')
      inquire (unit=unit, size=bytes)
      close (unit)
      mm = int(((bytes - 16)/nrec - 8)/8) - 2
   end function residual_count
   !> best.nml without its comment lines (which name the output folder)
   function body(text) result(rest)
      character(len=*), intent(in) :: text
      character(len=:), allocatable :: rest
      rest = text(max(index(text, '&constants'), 1):)
   end function body

   !> SIGTERM during a run: a line in fit.log, exit code 143, and --resume continues
   subroutine test_sigterm(error)
      type(error_type), allocatable, intent(out) :: error
      character(len=:), allocatable :: exe, input, dir, log
      integer :: stat
      exe = usharp_exe()
      if (len(exe) == 0) then
         call skip_test(error, 'the usharp executable was not found beside the tester')
         return
      end if
      input = deck('sigterm.nml', 'eps=1e-300, max_evals=300', '')
      dir = scratch_dir//'/sigterm-out'
      stat = shell('rm -rf '//dir//'; '//exe//' run -q '//input//' -o '//dir//' > /dev/null 2>&1 & pid=$!; n=0; '// &
                   'while [ "$(cat '//dir//'/fit.journal 2>/dev/null | wc -l)" -lt 20 ] && [ $n -lt 3000 ]; '// &
                   'do sleep 0.01; n=$((n+1)); done; kill -TERM $pid; wait $pid; echo $? > '//dir//'.rc')
      call check(error, trim(read_text(dir//'.rc')) == '143'//new_line('a'), 'exit code 143, not '//read_text(dir//'.rc'))
      if (allocated(error)) return
      log = read_text(dir//'/fit.log')
      call check(error, index(log, 'stopped by signal 15 after ') > 0 .and. &
                 index(log, ' evaluations; continue with --resume') > 0, 'fit.log: '//log)
      if (allocated(error)) return
      stat = shell(exe//' run -q --resume '//input//' -o '//dir//' > /dev/null 2>&1')
      call check(error, stat, 0, 'resumed run')
   end subroutine test_sigterm

   !> The fit of input into folder full (--force), the reference a resumed run is held to;
   !> a failed test when it fails
   subroutine uninterrupted_run(input, full, summary, error)
      character(len=*), intent(in) :: input, full
      character(len=report_line_len), allocatable, intent(out) :: summary(:)
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: e
      call run_command(input, full, '', .false., summary, e, force=.true.)
      if (allocated(e)) call test_failed(error, 'uninterrupted run: '//e%message)
   end subroutine uninterrupted_run

end module test_safety
