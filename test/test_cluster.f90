!> Tests of the cluster job scripts (scripts/cluster): their syntax, and a job stopped by TERM
!> and started again ends where an uninterrupted run ends; and of MPI: the same work on 1 and
!> 2 ranks writes the same results and logs, bit for bit, and a 2-rank run stopped by TERM
!> goes on on 1 rank to the same end
module test_cluster
   use testdrive, only: error_type, unittest_type, new_unittest, check, test_failed, skip_test
   use usharp_error, only: uerror => error_type
   use usharp_filesys, only: make_dir
   use test_util, only: require_exe, read_text, scratch_dir, write_text
   use usharp_strings, only: str
   use test_diagnose, only: model_groups, small_matrix
   implicit none
   private
   public :: collect_cluster

   character(len=*), parameter :: scripts(*) = [character(len=40) :: &
      'scripts/cluster/usharp-job.sh', 'scripts/cluster/slurm-run.sbatch', &
      'scripts/cluster/slurm-array.sbatch', 'scripts/cluster/pbs-run.pbs', &
      'scripts/cluster/slurm-mpi.sbatch']

contains

   subroutine collect_cluster(testsuite)
      type(unittest_type), allocatable, intent(out) :: testsuite(:)
      testsuite = [ &
         new_unittest('job-scripts-parse', test_syntax), &
         new_unittest('job-stopped-by-term-resumes-to-same-result', test_restart), &
         new_unittest('job-script-run-as-a-copy-finds-its-helper', test_job_copy), &
         new_unittest('job-requeued-only-with-work-left', test_requeue_only_resumable), &
         new_unittest('mpi-multistart-same-on-1-2-and-3-ranks', test_mpi_multistart), &
         new_unittest('mpi-2-ranks-stopped-resume-on-1-rank', test_mpi_resume), &
         new_unittest('mpi-selfcheck-same-on-1-and-2-ranks', test_mpi_selfcheck), &
         new_unittest('mpi-design-same-on-1-and-2-ranks', test_mpi_design), &
         new_unittest('mpi-diagnose-same-on-1-and-2-ranks', test_mpi_diagnose), &
         new_unittest('diagnose-stopped-by-term-resumes-to-same-report', test_diagnose_resume), &
         new_unittest('diagnose-resume-refused-after-input-changed', test_diagnose_changed), &
         new_unittest('mpi-diagnose-2-ranks-stopped-resume-on-1-rank', test_mpi_diagnose_resume), &
         new_unittest('mpi-unequal-starts-dealt-same-on-1-and-2-ranks', test_mpi_unequal_starts), &
         new_unittest('mpi-one-start-lm-helped-same-on-1-and-2-ranks', test_mpi_helped), &
         new_unittest('mpi-external-command-not-told-the-job', test_mpi_external_env), &
         new_unittest('usr1-outside-a-fit-ends-as-term', test_usr1_as_term), &
         new_unittest('usr1-after-a-fit-ends-the-run-resume-completes', test_usr1_after_fit), &
         new_unittest('mpi-run-into-a-locked-or-unwritable-folder-exits', test_mpi_folder_refused)]
   end subroutine collect_cluster

   subroutine test_syntax(error)
      type(error_type), allocatable, intent(out) :: error
      integer :: k, stat
      do k = 1, size(scripts)
         call execute_command_line('bash -n '//trim(scripts(k))//' 2>/dev/null', exitstat=stat)
         call check(error, stat == 0, 'bash -n '//trim(scripts(k)))
         if (allocated(error)) return
      end do
   end subroutine test_syntax

   !> Thesis run 2 (1111 evaluations) through usharp-job.sh: stopped by TERM once 300
   !> evaluations are logged, then the same script again; its objective history and result
   !> are those of an uninterrupted run, bit for bit
   subroutine test_restart(error)
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: e
      character(len=:), allocatable :: exe, a, b, stop_script, fom_a, fom_b, log
      integer :: stat
      logical :: requeued
      call require_exe(exe, error)
      if (allocated(error)) return
      call make_dir(scratch_dir, e)
      a = scratch_dir//'/cluster-whole'
      b = scratch_dir//'/cluster-stopped'
      call execute_command_line('rm -rf '//a//' '//b//' '//b//'.requeued')
      call execute_command_line(exe//' run -q -o '//a//' decks/thesis-run2.nml > /dev/null', exitstat=stat)
      call check(error, stat == 0, 'uninterrupted run')
      if (allocated(error)) return
      ! Start the job, wait for 300 evaluations in FOM.TXT (at most 120 s), send TERM
      stop_script = 'USHARP='//exe//' USHARP_REQUEUE="touch '//b//'.requeued" '// &
         'bash scripts/cluster/usharp-job.sh decks/thesis-run2.nml '// &
         b//' 2> '//b//'.log & p=$!; n=0; '// &
         'while [ "$(cat '//b//'/FOM.TXT 2>/dev/null | wc -l)" -lt 300 ] && [ $n -lt 2400 ]; '// &
         'do sleep 0.05; n=$((n+1)); done; kill -TERM $p; wait $p; echo $? > '//b//'.rc1'
      call execute_command_line('bash -c '''//stop_script//'''', exitstat=stat)
      log = read_text(b//'.log')
      call check(error, index(log, 'stopped by TERM') > 0, 'first start not stopped by TERM: '//log)
      if (allocated(error)) return
      call check(error, index(read_text(b//'/fit.log'), 'finished') == 0, &
                 'the stopped run must not have finished')
      if (allocated(error)) return
      inquire (file=b//'.requeued', exist=requeued)
      call check(error, requeued, 'a run stopped with work left must be requeued: '//log)
      if (allocated(error)) return
      call execute_command_line('USHARP='//exe//' bash scripts/cluster/usharp-job.sh '// &
                                'decks/thesis-run2.nml '//b//' > /dev/null 2>> '//b//'.log', exitstat=stat)
      call check(error, stat == 0, 'second start: '//read_text(b//'.log'))
      if (allocated(error)) return
      call check(error, index(read_text(b//'/fit.log'), 'resumed') > 0, 'second start did not resume')
      if (allocated(error)) return
      fom_a = read_text(a//'/FOM.TXT')
      fom_b = read_text(b//'/FOM.TXT')
      call check(error, len(fom_a) > 0 .and. fom_a == fom_b, 'objective histories differ')
      if (allocated(error)) return
      call check(error, read_text(a//'/GUESS.TXT') == read_text(b//'/GUESS.TXT'), 'guesses differ')
   end subroutine test_restart

   !> A TERM to the job script requeues the job only when usharp ends with 128 + N (stopped with
   !> its journal written): not when it had just finished (0) or failed (1, 4), which a requeue
   !> would only repeat. A stand-in for usharp exits with a chosen code on TERM.
   subroutine test_requeue_only_resumable(error)
      type(error_type), allocatable, intent(out) :: error
      character(len=:), allocatable :: fake, dir, log
      integer, parameter :: codes(4) = [0, 1, 4, 143]
      integer :: k, stat
      logical :: requeued
      dir = scratch_dir//'/requeue'
      call execute_command_line('rm -rf '//dir//'; mkdir -p '//dir)
      fake = write_text('requeue/usharp', [character(len=60) :: '#!/bin/bash', &
         'trap ''exit $FAKE_RC'' TERM USR1', 'touch "$(dirname "$0")"/ready', &
         'while :; do sleep 0.02; done'])
      call execute_command_line('chmod +x '//fake)
      do k = 1, size(codes)
         call execute_command_line('rm -f '//dir//'/ready '//dir//'/requeued')
         call execute_command_line('bash -c ''FAKE_RC='//str(codes(k))//' USHARP='//fake// &
            ' USHARP_REQUEUE="touch '//dir//'/requeued" bash scripts/cluster/usharp-job.sh x.nml '// &
            dir//'/out 2> '//dir//'/log & p=$!; n=0; while [ ! -e '//dir//'/ready ] && [ $n -lt 400 ]; '// &
            'do sleep 0.02; n=$((n+1)); done; kill -TERM $p; wait $p''', exitstat=stat)
         log = read_text(dir//'/log')
         call check(error, stat == codes(k), 'exit '//str(codes(k))//' passed on as '//str(stat)//': '//log)
         if (allocated(error)) return
         inquire (file=dir//'/requeued', exist=requeued)
         call check(error, requeued .eqv. codes(k) > 128, 'usharp exit '//str(codes(k))//', requeued: '// &
                    merge('yes', 'no ', requeued)//'; '//log)
         if (allocated(error)) return
      end do
   end subroutine test_requeue_only_resumable

   !> A scheduler runs a copy of the job script from its spool folder, and a job may be
   !> submitted from anywhere: the SLURM script finds usharp-job.sh where scontrol says it was
   !> submitted from, or at USHARP_JOB; the PBS script at USHARP_JOB; without either, a usage
   !> error (exit 2) that names USHARP_JOB. (usharp is echo here: only the helper's start counts.)
   subroutine test_job_copy(error)
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: e
      character(len=:), allocatable :: d, run, here
      character(len=4096) :: cwd
      ! cmdstat: gfortran stops at an exit status of 127 (a shell's command not found) without it
      integer :: stat, cstat
      call make_dir(scratch_dir, e)
      call get_environment_variable('PWD', cwd)
      here = trim(cwd)
      d = here//'/'//scratch_dir//'/job-copy'
      call execute_command_line('rm -rf '//d//' && mkdir -p '//d//'/spool '//d//'/bin '//d//'/sub && '// &
         'cp scripts/cluster/slurm-run.sbatch '//d//'/spool/slurm_script && '// &
         'cp scripts/cluster/pbs-run.pbs '//d//'/spool/pbs_script && '// &
         'printf ''#!/bin/sh\necho "JobId=7 JobName=usharp"\necho "   Command='//here// &
         '/scripts/cluster/slurm-run.sbatch"\n'' > '//d//'/bin/scontrol && chmod +x '//d//'/bin/scontrol', &
         exitstat=stat, cmdstat=cstat)
      call check(error, stat == 0, 'spool folder')
      if (allocated(error)) return
      run = 'cd '//d//'/sub && env -u USHARP_JOB SLURM_JOB_ID=7 SLURM_SUBMIT_DIR='//d//'/sub USHARP=echo '
      ! scontrol names the submitted script
      call execute_command_line(run//'PATH='//d//'/bin:$PATH bash ../spool/slurm_script fit.nml > '// &
                                d//'/out1 2>&1', exitstat=stat, cmdstat=cstat)
      call check(error, stat == 0 .and. index(read_text(d//'/out1'), 'run --auto-resume -q fit.nml') > 0, &
                 'SLURM copy, scontrol: '//read_text(d//'/out1'))
      if (allocated(error)) return
      ! No scontrol, submitted from elsewhere: refused, naming USHARP_JOB; with it, found
      call execute_command_line(run//'PATH=/usr/bin:/bin bash ../spool/slurm_script fit.nml > '// &
                                d//'/out2 2>&1', exitstat=stat, cmdstat=cstat)
      call check(error, stat == 2 .and. index(read_text(d//'/out2'), 'set USHARP_JOB=') > 0, &
                 'SLURM copy, nothing to find it by: '//read_text(d//'/out2'))
      if (allocated(error)) return
      call execute_command_line(run//'USHARP_JOB='//here//'/scripts/cluster/usharp-job.sh PATH=/usr/bin:/bin '// &
                                'bash ../spool/slurm_script fit.nml > '//d//'/out3 2>&1', exitstat=stat, cmdstat=cstat)
      call check(error, stat == 0 .and. index(read_text(d//'/out3'), 'run --auto-resume -q fit.nml') > 0, &
                 'SLURM copy, USHARP_JOB: '//read_text(d//'/out3'))
      if (allocated(error)) return
      call execute_command_line('cd '//d//'/sub && env -u USHARP_JOB PBS_O_WORKDIR='//d//'/sub INPUT=fit.nml '// &
                                'USHARP=echo bash ../spool/pbs_script > '//d//'/out4 2>&1', exitstat=stat, cmdstat=cstat)
      call check(error, stat == 2 .and. index(read_text(d//'/out4'), 'USHARP_JOB=') > 0, &
                 'PBS copy, no USHARP_JOB: '//read_text(d//'/out4'))
      if (allocated(error)) return
      call execute_command_line('cd '//d//'/sub && PBS_O_WORKDIR='//d//'/sub INPUT=fit.nml USHARP=echo '// &
                                'USHARP_JOB='//here//'/scripts/cluster/usharp-job.sh bash ../spool/pbs_script > '// &
                                d//'/out5 2>&1', exitstat=stat, cmdstat=cstat)
      call check(error, stat == 0 .and. index(read_text(d//'/out5'), 'run --auto-resume -q fit.nml') > 0, &
                 'PBS copy, USHARP_JOB: '//read_text(d//'/out5'))
   end subroutine test_job_copy

   !> A 2-rank run into a folder another run holds exits 6, into one it cannot make exits 4,
   !> as one process does, every rank told (rank 1 had waited in the fit for ever)
   subroutine test_mpi_folder_refused(error)
      type(error_type), allocatable, intent(out) :: error
      character(len=:), allocatable :: exe, mpirun, d
      integer :: stat, cstat
      call require_mpirun(mpirun, error)
      if (allocated(error)) return
      call require_exe(exe, error)
      if (allocated(error)) return
      d = scratch_dir//'/mpi-locked'
      call execute_command_line('rm -rf '//d//' && mkdir -p '//d//' && : > '//d//'.file', exitstat=stat)
      ! (the lock held by flock for 20 s; timeout ends a run that would wait for ever)
      call execute_command_line('( flock 9; sleep 20 ) 9> '//d//'/.usharp.lock & sleep 1; '// &
                                'OMP_NUM_THREADS=1 timeout 15 '//mpirun(19:)//exe//' run -q -o '//d//' '// &
                                multistart_deck(2, 6)//' > /dev/null 2> '//d//'.log', exitstat=stat, cmdstat=cstat)
      call check(error, stat, 6, 'a locked folder: exit code ('//read_text(d//'.log')//')')
      if (allocated(error)) return
      call execute_command_line('OMP_NUM_THREADS=1 timeout 15 '//mpirun(19:)//exe//' run -q -o '//d// &
                                '.file '//multistart_deck(2, 6)//' > /dev/null 2> '//d//'.log', exitstat=stat, &
                                cmdstat=cstat)
      call check(error, stat, 4, 'an unwritable folder: exit code ('//read_text(d//'.log')//')')
   end subroutine test_mpi_folder_refused

   !> mpirun for np ranks (2 when absent) of one thread each, or a skip when there is none
   subroutine require_mpirun(mpirun, error, np)
      character(len=:), allocatable, intent(out) :: mpirun
      type(error_type), allocatable, intent(out) :: error
      integer, intent(in), optional :: np
      integer :: stat, n
      n = 2
      if (present(np)) n = np
      mpirun = 'OMP_NUM_THREADS=1 mpirun --allow-run-as-root --oversubscribe -np '//str(n)//' '
      call execute_command_line('command -v mpirun > /dev/null 2>&1', exitstat=stat)
      if (stat /= 0) call skip_test(error, 'mpirun not found (Open MPI: openmpi-bin)')
   end subroutine require_mpirun

   !> Thesis run 2's tests fitted by Levenberg-Marquardt from 20 starts of at most 30
   !> evaluations each (about 600 evaluations; on 2 ranks two chunks of starts, see
   !> tasks_per_share, so that a run can be stopped after the first is journaled)
   function multistart_deck(nstarts, max_evals) result(path)
      !> number of starts (0: one, from the deck's constants)
      integer, intent(in) :: nstarts
      !> at most this many evaluations per start (30 unless given)
      integer, intent(in), optional :: max_evals
      character(len=:), allocatable :: path
      character(len=4096) :: cwd
      integer :: most
      most = 30
      if (present(max_evals)) most = max_evals
      call get_environment_variable('PWD', cwd)
      path = write_text('mpi-multistart-'//str(nstarts)//'-'//str(most)//'.nml', [character(len=4200) :: &
         "&model name = 'miller', units = 'ksi', temperature = 866.15, tm = 1800.0, youngs = 22.5e3 /", &
         '&constants a1 = 1.0, a2 = 1.0e-5, b = 1.0e13, c2 = 0.1, h1 = 100.0, h2 = 100.0, n = 1.0, '// &
         'q = 91000.0 /', &
         "&fit fitted = 'A1', 'A2', 'B', 'C2', 'H1', 'H2', 'n', method = 'lm', multistart = "//str(nstarts)//", "// &
         "objective = 'eq7', max_evals = "//str(most)//", max_failures = 200 /", &
         "&test name = 'lcf', history = 'thesis_lcf', dt_out = 1.0, data_file = '"//trim(cwd)// &
         "/data/thesis/lcf.sim.txt', time_column = 'time', stress_column = 'stress', "// &
         "weighting = 'threshold', sig = 14.0 /", &
         "&test name = 'relax', history = 'relaxation', dt_out = 1.0, levels = 0.00075, 0.001, "// &
         "ramp_time = 1.0, holds = 600.0, 600.0, data_file = '"//trim(cwd)// &
         "/data/thesis/relax.sim.txt', time_column = 'time', stress_column = 'stress', "// &
         "weighting = 'relaxation' /"])
   end function multistart_deck

   !> Whether two files are the same byte for byte
   logical function same_file(a, b)
      character(len=*), intent(in) :: a, b
      integer :: stat
      call execute_command_line('cmp -s '//a//' '//b, exitstat=stat)
      same_file = stat == 0
   end function same_file

   !> The fit's logs and results in folders a and b are the same (best.nml from its third line:
   !> the second names the folder)
   subroutine check_same_fit(error, a, b)
      type(error_type), allocatable, intent(out) :: error
      character(len=*), intent(in) :: a, b
      character(len=*), parameter :: files(*) = [character(len=13) :: 'fit.journal', 'fit.cache', &
         'GUESS.TXT', 'FOM.TXT', 'SUMS.TXT', 'lcf.fit.txt', 'relax.fit.txt']
      integer :: k, stat
      do k = 1, size(files)
         call check(error, same_file(a//'/'//trim(files(k)), b//'/'//trim(files(k))), &
                    trim(files(k))//' differs between '//a//' and '//b)
         if (allocated(error)) return
      end do
      call execute_command_line('bash -c "cmp -s <(tail -n +3 '//a//'/best.nml) <(tail -n +3 '//b// &
                                '/best.nml)"', exitstat=stat)
      call check(error, stat == 0, 'best.nml differs between '//a//' and '//b)
   end subroutine check_same_fit

   !> The usharp executable, mpirun, the multi-start deck with nstarts starts, and its fit on
   !> 1 rank into folder a (b removed for the run to compare), or a skip or failure
   subroutine reference_fit(exe, mpirun, deck, nstarts, a, b, error)
      character(len=:), allocatable, intent(out) :: exe, mpirun, deck
      integer, intent(in) :: nstarts
      character(len=*), intent(in) :: a, b
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: e
      integer :: stat
      call require_exe(exe, error)
      if (allocated(error)) return
      call require_mpirun(mpirun, error)
      if (allocated(error)) return
      call make_dir(scratch_dir, e)
      deck = multistart_deck(nstarts)
      call execute_command_line('rm -rf '//a//' '//b//' '//b//'.log')
      call execute_command_line('OMP_NUM_THREADS=1 '//exe//' run -q -o '//a//' '//deck//' > /dev/null', &
                                exitstat=stat)
      call check(error, stat == 0, 'the fit on 1 rank')
   end subroutine reference_fit

   !> A multi-start fit on 1, 2 and 3 ranks: the same journal, cache, logs and result (on 3
   !> ranks two of them send rank 0 the starts they ended, which it logs without searching
   !> them again, the fit's last start apart)
   subroutine test_mpi_multistart(error)
      type(error_type), allocatable, intent(out) :: error
      character(len=:), allocatable :: exe, mpirun, mpirun3, deck, a, b, c
      integer :: stat
      a = scratch_dir//'/mpi-ms-1'
      b = scratch_dir//'/mpi-ms-2'
      c = scratch_dir//'/mpi-ms-3'
      call reference_fit(exe, mpirun, deck, 20, a, b, error)
      if (allocated(error)) return
      call execute_command_line(mpirun//exe//' run -q -o '//b//' '//deck//' > /dev/null', exitstat=stat)
      call check(error, stat == 0, '2 ranks')
      if (allocated(error)) return
      call check(error, index(read_text(a//'/fit.log'), 'multi-start 20 of 20') > 0, 'not 20 starts')
      if (allocated(error)) return
      call check_same_fit(error, a, b)
      if (allocated(error)) return
      call check(error, same_file(a//'/fit.log', b//'/fit.log'), 'fit.log differs')
      if (allocated(error)) return
      call require_mpirun(mpirun3, error, 3)
      if (allocated(error)) return
      call execute_command_line('rm -rf '//c//'; '//mpirun3//exe//' run -q -o '//c//' '// &
                                deck//' > /dev/null', exitstat=stat)
      call check(error, stat == 0, '3 ranks')
      if (allocated(error)) return
      call check_same_fit(error, a, c)
      if (allocated(error)) return
      call check(error, same_file(a//'/fit.log', c//'/fit.log'), 'fit.log differs on 3 ranks')
   end subroutine test_mpi_multistart

   !> A 2-rank multi-start fit started by the job script (usharp-job.sh through mpirun), stopped
   !> by TERM once its first starts are logged, resumed on 1 rank: the logs and result of an
   !> uninterrupted run
   subroutine test_mpi_resume(error)
      type(error_type), allocatable, intent(out) :: error
      character(len=:), allocatable :: exe, mpirun, deck, a, b, stop_script
      integer :: stat
      a = scratch_dir//'/mpi-rs-whole'
      b = scratch_dir//'/mpi-rs-stopped'
      ! 64 starts: 2 ranks journal them in chunks of 16, so the TERM after the first chunk
      ! comes with three chunks still to run
      call reference_fit(exe, mpirun, deck, 64, a, b, error)
      if (allocated(error)) return
      ! The job script with 2 ranks: wait until the first chunk of starts is in the journal
      ! (at most 120 s), then TERM the script, which passes it on through mpirun
      stop_script = 'USHARP='//exe//' USHARP_THREADS=1 USHARP_LAUNCHER="'//mpirun(19:)//'" '// &
         'bash scripts/cluster/usharp-job.sh '//deck//' '//b//' > /dev/null 2> '//b//'.log & p=$!; n=0; '// &
         'while [ "$(cat '//b//'/fit.journal 2>/dev/null | grep -vc ^#)" -lt 1 ] && [ $n -lt 2400 ]; '// &
         'do sleep 0.05; n=$((n+1)); done; kill -TERM $p; wait $p'
      call execute_command_line('bash -c '''//stop_script//'''', exitstat=stat)
      call check(error, index(read_text(b//'.log'), 'stopped by signal 15') > 0, &
                 'the 2-rank run was not stopped by TERM: '//read_text(b//'.log'))
      if (allocated(error)) return
      call check(error, index(read_text(b//'/fit.log'), 'finished') == 0, &
                 'the stopped run must not have finished')
      if (allocated(error)) return
      call execute_command_line('OMP_NUM_THREADS=1 '//exe//' run -q --resume -o '//b//' '//deck// &
                                ' > /dev/null 2>> '//b//'.log', exitstat=stat)
      call check(error, stat == 0, 'resume on 1 rank: '//read_text(b//'.log'))
      if (allocated(error)) return
      call check(error, index(read_text(b//'/fit.log'), 'resumed') > 0, 'did not resume')
      if (allocated(error)) return
      call check_same_fit(error, a, b)
   end subroutine test_mpi_resume


   !> Five starts of unequal cost (their simulations take longer or shorter with their
   !> constants; each start goes to the rank that is free first, so the ranks that run them
   !> depend on the timing): the same journal, cache, logs, result and identifiability report (its Jacobian's
   !> points split over the ranks) as 1 rank
   subroutine test_mpi_unequal_starts(error)
      type(error_type), allocatable, intent(out) :: error
      call check_same_on_ranks(error, 'mpi-unequal', 'run '//multistart_deck(5, 60), [character(len=20) :: &
         'fit.journal', 'fit.cache', 'fit.log', 'GUESS.TXT', 'FOM.TXT', 'identify.txt'])
      if (allocated(error)) return
      call check(error, index(read_text(scratch_dir//'/mpi-unequal-2/summary.txt'), 'identifiability') > 0, &
                 'no identifiability report in the 2-rank summary')
   end subroutine test_mpi_unequal_starts

   !> A Levenberg-Marquardt fit of one start on 2 ranks: rank 0 searches, rank 1 simulates
   !> its share of every difference Jacobian's points (it has no start of its own, so it
   !> helps from the first Jacobian on, whatever the timing): the journal, cache, logs,
   !> result and report of 1 rank, bit for bit, and the summary counts rank 1's points
   subroutine test_mpi_helped(error)
      type(error_type), allocatable, intent(out) :: error
      character(len=:), allocatable :: summary, tail
      character(len=*), parameter :: key = 'ranks 2; simulated for another rank''s search: 0, '
      character(len=*), parameter :: shares = 'a share of the tests of 0, '
      integer :: at, n, m, stat
      call check_same_on_ranks(error, 'mpi-helped', 'run '//multistart_deck(0, 40), [character(len=20) :: &
         'fit.journal', 'fit.cache', 'fit.log', 'GUESS.TXT', 'FOM.TXT', 'SUMS.TXT', 'identify.txt'])
      if (allocated(error)) return
      summary = read_text(scratch_dir//'/mpi-helped-2/summary.txt')
      at = index(summary, key)
      call check(error, at > 0, 'no count of the helped points in the 2-rank summary')
      if (allocated(error)) return
      tail = summary(at + len(key):)
      read (tail, *, iostat=stat) n
      call check(error, stat == 0, 'no count of rank 1''s points: '//tail)
      if (allocated(error)) return
      ! Points simulated whole, and points of which rank 1 took a share of the tests
      at = index(tail, shares)
      if (at > 0) then
         read (tail(at + len(shares):), *, iostat=stat) m
         call check(error, stat == 0, 'no count of rank 1''s shares: '//tail)
         if (allocated(error)) return
         n = n + m
      end if
      call check(error, n > 0, 'rank 1 simulated no point for rank 0: '//tail)
   end subroutine test_mpi_helped

   !> A command on 1 rank and on 2 ranks into two folders; the files named must be the same
   !> (the self-check's report after its time is taken out)
   subroutine check_same_on_ranks(error, name, command, files)
      type(error_type), allocatable, intent(out) :: error
      character(len=*), intent(in) :: name, command, files(:)
      type(uerror), allocatable :: e
      character(len=:), allocatable :: exe, mpirun, a, b
      integer :: stat, k
      call require_exe(exe, error)
      if (allocated(error)) return
      call require_mpirun(mpirun, error)
      if (allocated(error)) return
      call make_dir(scratch_dir, e)
      a = scratch_dir//'/'//name//'-1'
      b = scratch_dir//'/'//name//'-2'
      call execute_command_line('rm -rf '//a//' '//b)
      call execute_command_line('OMP_NUM_THREADS=1 '//exe//' '//command//' -q -o '//a//' > /dev/null', &
                                exitstat=stat)
      call check(error, stat == 0, name//' on 1 rank')
      if (allocated(error)) return
      call execute_command_line(mpirun//exe//' '//command//' -q -o '//b//' > /dev/null', exitstat=stat)
      call check(error, stat == 0, name//' on 2 ranks')
      if (allocated(error)) return
      do k = 1, size(files)
         call execute_command_line('bash -c "cmp -s <(sed ''s/ in [0-9.]* s$//'' '//a//'/'// &
            trim(files(k))//') <(sed ''s/ in [0-9.]* s$//'' '//b//'/'//trim(files(k))//')"', exitstat=stat)
         call check(error, stat == 0, trim(files(k))//' differs between 1 and 2 ranks ('//a//', '//b//')')
         if (allocated(error)) return
      end do
   end subroutine check_same_on_ranks

   !> A self-check subset (clean data and three effects, one repetition each, the small matrix
   !> of the diagnosis tests) on 1 and 2 ranks: the same journal and report
   subroutine test_mpi_selfcheck(error)
      type(error_type), allocatable, intent(out) :: error
      character(len=:), allocatable :: deck
      deck = write_text('mpi-selfcheck.nml', [character(len=100) :: model_groups, small_matrix])
      call check_same_on_ranks(error, 'mpi-selfcheck', 'diagnose --selfcheck '//deck, &
                               [character(len=20) :: 'selfcheck.journal', 'selfcheck.md'])
   end subroutine test_mpi_selfcheck

   !> A design of one current test and three candidates on 1 and 2 ranks: the same journal
   !> and ranking
   subroutine test_mpi_design(error)
      type(error_type), allocatable, intent(out) :: error
      character(len=:), allocatable :: deck
      deck = write_text('mpi-design.nml', [character(len=100) :: model_groups, &
         "&fit fitted = 'B', 'C2', 'H1', 'n' /", &
         "&test name = 'cyc', history = 'cyclic', strain_range = 0.01, strain_rate = 1e-3,", &
         "  cycles = 2, dt_out = 0.5 /", &
         "&test name = 'relax', history = 'relaxation', candidate = .true., holds = 100.0, 100.0 /", &
         "&test name = 'cyc2', history = 'cyclic', strain_range = 0.02, strain_rate = 1e-3,", &
         "  cycles = 2, dt_out = 0.5, candidate = .true. /", &
         "&test name = 'hold', history = 'cyclic', strain_range = 0.01, strain_rate = 1e-3,", &
         "  cycles = 1, dt_out = 0.5, hold_max = 100.0, candidate = .true. /"])
      call check_same_on_ranks(error, 'mpi-design', 'design '//deck, &
                               [character(len=20) :: 'design.journal', 'design.txt'])
   end subroutine test_mpi_design

   !> The thesis diagnosis (decks/thesis-diagnose.nml) with a baseline from 2 Latin-hypercube
   !> starts besides the deck's constants (so that its baseline's starts are spread over the
   !> ranks), written as scratch_dir/name; data: the folder of its data files
   function diagnose_deck(name, data) result(deck)
      character(len=*), intent(in) :: name, data
      character(len=:), allocatable :: deck
      deck = write_text(name, [character(len=4200) :: model_groups, &
         "&fit fitted = 'A1', 'A2', 'B', 'C2', 'H1', 'H2', 'n', method = 'lm', multistart = 2 /", &
         "&diagnose holdout = 'ratchet' /", &
         "&test name = 'lcf', history = 'thesis_lcf', dt_out = 0.5, amp_first = 0.0005, "// &
         "amp_last = 0.005, npeaks = 12, quarter_time = 10.0, weighting = 'threshold', sig = 14.0, "// &
         "data_file = '"//data//"/lcf.sim.txt' /", &
         "&test name = 'relax', history = 'relaxation', dt_out = 1.0, weighting = 'relaxation', "// &
         "levels = 0.00075, 0.001, ramp_time = 1.0, holds = 600.0, 600.0, "// &
         "data_file = '"//data//"/relax.sim.txt' /", &
         "&test name = 'ratchet', history = 'ratchet', dt_out = 1.0, up = 0.0005, down = 0.00025, "// &
         "repeats = 15, seg_time = 40.0, data_file = '"//data//"/ratchet.sim.txt' /"])
   end function diagnose_deck

   !> The data folder of the thesis diagnosis (absolute)
   function thesis_data() result(data)
      character(len=:), allocatable :: data
      character(len=4096) :: cwd
      call get_environment_variable('PWD', cwd)
      data = trim(cwd)//'/data/thesis-noise1'
   end function thesis_data

   !> The diagnosis of diagnose_deck on 1 and 2 ranks: the same report, tables and journal
   subroutine test_mpi_diagnose(error)
      type(error_type), allocatable, intent(out) :: error
      call check_same_on_ranks(error, 'mpi-diagnose', 'diagnose '//diagnose_deck('mpi-diagnose.nml', &
         thesis_data()), [character(len=30) :: 'diagnose/report.md', 'diagnose/effects.csv', &
         'diagnose/regions.csv', 'diagnose/residuals.csv', 'diagnose/diagnose.journal'])
   end subroutine test_mpi_diagnose

   !> The files a diagnosis writes in folders a and b are the same (steps.csv without its
   !> times)
   subroutine check_same_diagnosis(error, a, b)
      type(error_type), allocatable, intent(out) :: error
      character(len=*), intent(in) :: a, b
      character(len=*), parameter :: files(*) = [character(len=16) :: 'report.md', 'effects.csv', &
         'regions.csv', 'residuals.csv', 'diagnose.journal']
      integer :: k, stat
      do k = 1, size(files)
         call check(error, same_file(a//'/diagnose/'//trim(files(k)), b//'/diagnose/'//trim(files(k))), &
                    trim(files(k))//' differs from the uninterrupted diagnosis ('//a//', '//b//')')
         if (allocated(error)) return
      end do
      call execute_command_line('bash -c "cmp -s <(cut -d, -f1,2 '//a//'/diagnose/steps.csv) '// &
                                '<(cut -d, -f1,2 '//b//'/diagnose/steps.csv)"', exitstat=stat)
      call check(error, stat == 0, 'the simulations of each step differ (steps.csv)')
   end subroutine check_same_diagnosis

   !> Start `command` (the diagnosis into folder b) in the background, wait until its journal
   !> holds `units` whole units (at most 120 s), send TERM; its stderr goes to b.log, its exit
   !> status to b.rc
   subroutine stop_diagnosis(command, b, units)
      character(len=*), intent(in) :: command, b
      integer, intent(in) :: units
      character(len=:), allocatable :: script
      script = command//' > /dev/null 2> '//b//'.log & p=$!; n=0; '// &
         'while [ "$(cat '//b//'/diagnose/diagnose.journal 2>/dev/null | grep -c ^end)" -lt '//str(units)// &
         ' ] && [ $n -lt 2400 ]; do sleep 0.05; n=$((n+1)); done; kill -TERM $p; wait $p; '// &
         'echo $? > '//b//'.rc'
      call execute_command_line('bash -c '''//script//'''')
   end subroutine stop_diagnosis

   !> The number in a file ('' or unreadable: -1)
   integer function number_in(path) result(n)
      character(len=*), intent(in) :: path
      character(len=:), allocatable :: text
      integer :: ios
      n = -1
      text = read_text(path)
      read (text, *, iostat=ios) n
      if (ios /= 0) n = -1
   end function number_in

   !> The usharp executable, diagnose_deck as scratch_dir/name.nml, and its diagnosis on 1
   !> rank into scratch_dir/name-whole (a; b: name-stopped, removed), or a skip or failure
   subroutine reference_diagnosis(name, exe, deck, a, b, error)
      character(len=*), intent(in) :: name
      character(len=:), allocatable, intent(out) :: exe, deck, a, b
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: e
      integer :: stat
      call require_exe(exe, error)
      if (allocated(error)) return
      call make_dir(scratch_dir, e)
      exe = 'OMP_NUM_THREADS=1 '//exe
      deck = diagnose_deck(name//'.nml', thesis_data())
      a = scratch_dir//'/'//name//'-whole'
      b = scratch_dir//'/'//name//'-stopped'
      call execute_command_line('rm -rf '//a//' '//b)
      call execute_command_line(exe//' diagnose -q -o '//a//' '//deck//' > /dev/null', exitstat=stat)
      call check(error, stat == 0, 'uninterrupted diagnosis')
   end subroutine reference_diagnosis

   !> A whole diagnosis and the same stopped by TERM after 10 of its units are journaled:
   !> exit 143 naming --resume, no report; a start without --resume is refused; --resume
   !> writes the report, tables and journal of the whole one, bit for bit
   subroutine test_diagnose_resume(error)
      type(error_type), allocatable, intent(out) :: error
      character(len=:), allocatable :: exe, deck, a, b
      integer :: stat
      call reference_diagnosis('diagnose-resume', exe, deck, a, b, error)
      if (allocated(error)) return
      call stop_diagnosis(exe//' diagnose -q -o '//b//' '//deck, b, 10)
      call check(error, number_in(b//'.rc') == 143, 'the diagnosis stopped by TERM must exit 143, not '// &
                 read_text(b//'.rc')//read_text(b//'.log'))
      if (allocated(error)) return
      call check(error, index(read_text(b//'.log'), 'continue with --resume') > 0, &
                 'no message naming --resume: '//read_text(b//'.log'))
      if (allocated(error)) return
      call check(error, len(read_text(b//'/diagnose/report.md')) == 0, 'the stopped diagnosis wrote a report')
      if (allocated(error)) return
      call execute_command_line(exe//' diagnose -q -o '//b//' '//deck//' > /dev/null 2>> '//b//'.log', &
                                exitstat=stat)
      call check(error, stat == 2, 'a start over the journal without --resume or --force must be refused')
      if (allocated(error)) return
      call execute_command_line(exe//' diagnose -q --resume -o '//b//' '//deck//' > /dev/null 2>> '// &
                                b//'.log', exitstat=stat)
      call check(error, stat == 0, 'resume: '//read_text(b//'.log'))
      if (allocated(error)) return
      call check_same_diagnosis(error, a, b)
   end subroutine test_diagnose_resume

   !> A stopped diagnosis resumed after its deck changed, or after a data file changed: a
   !> one-line input error naming the journal; with the input as it was it resumes
   subroutine test_diagnose_changed(error)
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: e
      character(len=:), allocatable :: exe, deck, b, data, log, j
      integer :: stat
      character(len=4096) :: cwd
      call require_exe(exe, error)
      if (allocated(error)) return
      call make_dir(scratch_dir, e)
      exe = 'OMP_NUM_THREADS=1 '//exe
      ! The data copied, so that one of them can change
      call get_environment_variable('PWD', cwd)
      data = trim(cwd)//'/'//scratch_dir//'/diagnose-changed-data'
      call execute_command_line('rm -rf '//data//'; mkdir -p '//data//'; cp '//thesis_data()//'/*.txt '//data)
      deck = diagnose_deck('diagnose-changed.nml', data)
      b = scratch_dir//'/diagnose-changed'
      call execute_command_line('rm -rf '//b)
      call stop_diagnosis(exe//' diagnose -q -o '//b//' '//deck, b, 3)
      call check(error, number_in(b//'.rc') == 143, 'not stopped by TERM: '//read_text(b//'.log'))
      if (allocated(error)) return
      ! A journal of another layout of the units (its fingerprint without this layout's tag)
      j = b//'/diagnose/diagnose.journal'
      call execute_command_line('cp '//j//' '//j//'.kept; sed -i ''1s/ units=[0-9]*//'' '//j)
      call execute_command_line(exe//' diagnose -q --resume -o '//b//' '//deck//' > /dev/null 2> '// &
                                b//'.log2', exitstat=stat)
      call execute_command_line('mv '//j//'.kept '//j)
      log = read_text(b//'.log2')
      call check(error, stat == 1 .and. index(log, "cannot resume: the layout of the journal's units changed") > 0, &
                 'journal of another layout: exit '//str(stat)//', '//log)
      if (allocated(error)) return
      ! The deck changed (a comment added)
      call execute_command_line('echo "! changed" >> '//deck)
      call execute_command_line(exe//' diagnose -q --resume -o '//b//' '//deck//' > /dev/null 2> '// &
                                b//'.log2', exitstat=stat)
      log = read_text(b//'.log2')
      call check(error, stat == 1 .and. index(log, b//'/diagnose/diagnose.journal: cannot resume: the input file') > 0 &
                 .and. index(log, new_line('a')) == len(log), 'changed deck: exit '//str(stat)//', '//log)
      if (allocated(error)) return
      ! The deck as it was, a data file changed (its last line dropped)
      deck = diagnose_deck('diagnose-changed.nml', data)
      call execute_command_line('sed -i ''$d'' '//data//'/relax.sim.txt')
      call execute_command_line(exe//' diagnose -q --resume -o '//b//' '//deck//' > /dev/null 2> '// &
                                b//'.log2', exitstat=stat)
      log = read_text(b//'.log2')
      call check(error, stat == 1 .and. index(log, b//'/diagnose/diagnose.journal: cannot resume') > 0, &
                 'changed data file: exit '//str(stat)//', '//log)
      if (allocated(error)) return
      ! With the data as they were, the journal resumes
      call execute_command_line('cp '//thesis_data()//'/relax.sim.txt '//data)
      call stop_diagnosis(exe//' diagnose -q --resume -o '//b//' '//deck, b, 5)
      call check(error, number_in(b//'.rc') == 143, 'the unchanged input must resume: '//read_text(b//'.log'))
   end subroutine test_diagnose_changed

   !> The diagnosis of diagnose_deck on 2 ranks stopped by TERM (to mpirun, which passes it
   !> on) once 10 units are journaled, resumed on 1 rank: the report, tables and journal of an
   !> uninterrupted diagnosis on 1 rank
   subroutine test_mpi_diagnose_resume(error)
      type(error_type), allocatable, intent(out) :: error
      character(len=:), allocatable :: exe, mpirun, deck, a, b
      integer :: stat
      call require_mpirun(mpirun, error)
      if (allocated(error)) return
      call reference_diagnosis('mpi-diagnose-resume', exe, deck, a, b, error)
      if (allocated(error)) return
      ! (exe begins with OMP_NUM_THREADS=1, which mpirun's environment has already)
      call stop_diagnosis(mpirun//exe(19:)//' diagnose -q -o '//b//' '//deck, b, 10)
      call check(error, index(read_text(b//'.log'), 'continue with --resume') > 0 .and. &
                 number_in(b//'.rc') /= 0, 'the 2-rank diagnosis was not stopped by TERM: '//read_text(b//'.log'))
      if (allocated(error)) return
      call execute_command_line(exe//' diagnose -q --resume -o '//b//' '//deck//' > /dev/null 2>> '// &
                                b//'.log', exitstat=stat)
      call check(error, stat == 0, 'resume on 1 rank: '//read_text(b//'.log'))
      if (allocated(error)) return
      call check_same_diagnosis(error, a, b)
   end subroutine test_mpi_diagnose_resume
   !> An external command started from a rank is not given the variables by which mpirun
   !> places a process in its job: a usharp started there (the ANSYS stand-in) would take them
   !> for its own, fail to join, and leave the ranks waiting for it to the end
   subroutine test_mpi_external_env(error)
      type(error_type), allocatable, intent(out) :: error
      character(len=:), allocatable :: exe, mpirun, deck, dir, envfile
      character(len=4096) :: cwd
      integer :: stat
      call require_exe(exe, error)
      if (allocated(error)) return
      call require_mpirun(mpirun, error)
      if (allocated(error)) return
      call get_environment_variable('PWD', cwd)
      dir = trim(cwd)//'/'//scratch_dir//'/mpi-ext-env'
      envfile = dir//'.env'
      call execute_command_line('rm -rf '//dir//' '//envfile)
      deck = write_text('mpi-ext-env.nml', [character(len=600) :: &
         "&model name='miller', units='ksi', temperature=866.15, tm=1800.0, youngs=22.5e3 /", &
         '&constants a1=0.8, a2=7.42e-5, b=1e15, c2=0.1, h1=200, h2=100, n=5.0, q=91000 /', &
         "&fit fitted='H1','n', max_evals=1, identify=.false. /", &
         "&test name='lcf', history='thesis_lcf', data_file='"//trim(cwd)//"/data/thesis/lcf.sim.txt', "// &
         "dt_out=4.0, backend='external', command='env > "//envfile//"; exit 1' /"])
      ! (the start fails as the command does: exit 3, in a time limit that a hang would pass)
      call execute_command_line('timeout 120 env '//mpirun//exe//' run -q -o '//dir//' '//deck// &
                                ' > /dev/null 2>&1', exitstat=stat)
      call check(error, stat, 3, 'the run ends as its start fails (124: it hung)')
      if (allocated(error)) return
      call check(error, index(read_text(envfile), 'PATH=') > 0, 'the command ran with an environment')
      if (allocated(error)) return
      call execute_command_line("grep -q -E '^(OMPI|PMIX|PMI|PRTE)_' "//envfile, exitstat=stat)
      call check(error, stat /= 0, 'the command was given mpirun''s variables')
   end subroutine test_mpi_external_env

   !> A job script stops ranks with SIGUSR1 (see usharp-job.sh). Outside a fit, which catches
   !> it, the program ends as SIGTERM ends it (exit 143, not 138): here a long simulation,
   !> signalled once it runs, writes no result
   subroutine test_usr1_as_term(error)
      type(error_type), allocatable, intent(out) :: error
      character(len=:), allocatable :: exe, deck, dir
      integer :: stat
      call require_exe(exe, error)
      if (allocated(error)) return
      dir = scratch_dir//'/usr1-simulate'
      call execute_command_line('rm -rf '//dir//' '//dir//'.rc')
      ! 200000 cycles: about 20 s in a release build, far longer than the wait below
      deck = write_text('usr1-simulate.nml', [character(len=200) :: &
         '&model temperature=866.15, tm=1800.0, youngs=22.5e3 /', &
         '&constants a1=0.8, a2=7.42e-5, b=1e15, c2=0.1, h1=280, h2=100, n=5.8, q=91000 /', &
         "&test name='long', history='cyclic', dt_out=1000.0, strain_range=0.01, "// &
         'strain_rate=1e-3, cycles=200000 /'])
      call execute_command_line('bash -c '''//exe//' simulate -q -o '//dir//' '//deck// &
         ' & p=$!; sleep 1; kill -0 $p && kill -USR1 $p; wait $p; echo $? > '//dir//'.rc''', exitstat=stat)
      call check(error, number_in(dir//'.rc'), 143, 'exit status after SIGUSR1 (143: 128 + SIGTERM)')
      if (allocated(error)) return
      call execute_command_line('test -e '//dir//'/long.sim.txt', exitstat=stat)
      call check(error, stat /= 0, 'a stopped simulation wrote its result')
   end subroutine test_usr1_as_term

   !> SIGUSR1 once a fit's best.nml is written (its curves being written, or its
   !> identifiability report being made): the run ends with exit 143, without identify.txt
   !> or summary.txt and without a part-written file; --resume makes them
   subroutine test_usr1_after_fit(error)
      type(error_type), allocatable, intent(out) :: error
      character(len=:), allocatable :: exe, deck, dir
      character(len=2000), allocatable :: lines(:)
      character(len=4096) :: cwd
      integer :: stat, k
      call require_exe(exe, error)
      if (allocated(error)) return
      call get_environment_variable('PWD', cwd)
      dir = scratch_dir//'/usr1-after-fit'
      call execute_command_line('rm -rf '//dir//' '//dir//'.rc')
      ! 40 tests at a tight tolerance: writing their curves and the report takes seconds
      allocate (lines(0))
      lines = [character(len=2000) :: &
         "&model name='miller', units='ksi', temperature=866.15, tm=1800.0, youngs=22.5e3 /", &
         '&constants a1=1.0, a2=1e-5, b=1e13, c2=0.1, h1=100, h2=100, n=1.0, q=91000 /', &
         '&solver rtol=1e-9, atol_strain=1e-12 /', &
         "&fit fitted='A1','A2','B','C2','H1','H2','n', method='hooke-jeeves', max_evals=3 /"]
      do k = 1, 20
         lines = [character(len=2000) :: lines, "&test name='lcf"//str(k)//"', history='thesis_lcf', "// &
            "dt_out=1.0, data_file='"//trim(cwd)//"/data/thesis/lcf.sim.txt', weighting='threshold', sig=14 /", &
            "&test name='relax"//str(k)//"', history='relaxation', dt_out=1.0, levels=0.00075, 0.001, "// &
            "ramp_time=1.0, holds=600.0, 600.0, data_file='"//trim(cwd)//"/data/thesis/relax.sim.txt', "// &
            "weighting='relaxation' /"]
      end do
      deck = write_text('usr1-after-fit.nml', lines)
      call execute_command_line('bash -c '''//exe//' run -q -o '//dir//' '//deck//' > /dev/null 2>&1 & '// &
         'p=$!; n=0; while [ ! -e '//dir//'/best.nml ] && [ $n -lt 2400 ]; do sleep 0.05; n=$((n+1)); done; '// &
         'kill -USR1 $p; wait $p; echo $? > '//dir//'.rc''', exitstat=stat)
      call check(error, number_in(dir//'.rc'), 143, 'exit status after SIGUSR1 past the fit')
      if (allocated(error)) return
      call execute_command_line('test -e '//dir//'/summary.txt -o -e '//dir//'/identify.txt || '// &
                                'ls '//dir//' | grep -q "\.part$"', exitstat=stat)
      call check(error, stat /= 0, 'a stopped run wrote its summary or report, or left a part-written file')
      if (allocated(error)) return
      call execute_command_line(exe//' run -q --resume -o '//dir//' '//deck//' > /dev/null 2>&1', exitstat=stat)
      call check(error, stat == 0, '--resume after the stop')
      if (allocated(error)) return
      call execute_command_line('test -s '//dir//'/summary.txt -a -s '//dir//'/identify.txt', exitstat=stat)
      call check(error, stat == 0, '--resume made no summary or report')
   end subroutine test_usr1_after_fit

end module test_cluster
