!> Tests of the cluster job scripts (scripts/cluster): their syntax, and a job stopped by TERM
!> and started again ends where an uninterrupted run ends
module test_cluster
   use testdrive, only: error_type, unittest_type, new_unittest, check, test_failed, skip_test
   use usharp_error, only: uerror => error_type
   use usharp_filesys, only: make_dir
   use test_util, only: require_exe, read_text, scratch_dir
   implicit none
   private
   public :: collect_cluster

   character(len=*), parameter :: scripts(*) = [character(len=40) :: &
      'scripts/cluster/usharp-job.sh', 'scripts/cluster/slurm-run.sbatch', &
      'scripts/cluster/slurm-array.sbatch', 'scripts/cluster/pbs-run.pbs']

contains

   subroutine collect_cluster(testsuite)
      type(unittest_type), allocatable, intent(out) :: testsuite(:)
      testsuite = [ &
         new_unittest('job-scripts-parse', test_syntax), &
         new_unittest('job-stopped-by-term-resumes-to-same-result', test_restart)]
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
      call require_exe(exe, error)
      if (allocated(error)) return
      call make_dir(scratch_dir, e)
      a = scratch_dir//'/cluster-whole'
      b = scratch_dir//'/cluster-stopped'
      call execute_command_line('rm -rf '//a//' '//b)
      call execute_command_line(exe//' run -q -o '//a//' decks/thesis-run2.nml > /dev/null', exitstat=stat)
      call check(error, stat == 0, 'uninterrupted run')
      if (allocated(error)) return
      ! Start the job, wait for 300 evaluations in FOM.TXT (at most 120 s), send TERM
      stop_script = 'USHARP='//exe//' bash scripts/cluster/usharp-job.sh decks/thesis-run2.nml '// &
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
end module test_cluster
