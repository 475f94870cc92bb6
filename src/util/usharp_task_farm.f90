!> Independent tasks (the repetitions of the self-check, the tests of a design) spread over the
!> MPI ranks in chunks, each task to the next rank that is free (OpenMP threads inside each
!> task), with their results kept
!> in a journal in the order of the tasks: every rank receives every result, rank 0 alone
!> writes, and a stopped run continues (--resume) on any number of ranks. A result is text
!> (numbers written at full precision), and the caller reads every result back from that text,
!> computed or replayed, so the outcome does not depend on the number of ranks or on a resume.
!> The journal: usharp_journal.
module usharp_task_farm
   use usharp_error, only: error_type, fatal_error
   use usharp_strings, only: str
   use usharp_journal, only: task_text, journal_file
   use usharp_signal, only: catch_stop_signals, release_stop_signals, stop_signal
   use usharp_mpi, only: n_ranks, this_rank, is_root, share, any_rank, parallel_sync, &
                         tasks_per_share, task_deal, ranks_that_ran
   implicit none
   private

   public :: task_list, task_text, run_tasks

   !> The tasks: run(k) computes task k and returns its result as lines of text
   type, abstract :: task_list
   contains
      procedure(task_run), deferred :: run
   end type task_list

   abstract interface
      !> Task k's result, as lines each ended by new_line('a')
      subroutine task_run(self, k, text, error)
         import :: task_list, error_type
         class(task_list), intent(inout) :: self
         integer, intent(in) :: k
         character(len=:), allocatable, intent(out) :: text
         type(error_type), allocatable, intent(out) :: error
      end subroutine task_run
   end interface

   !> A task not run (after an error or a stop on its rank)
   integer, parameter :: stat_not_run = -2

contains

   !> Run tasks 1 to ntasks (over the ranks) into results. journal: its path ('' for none);
   !> mode: 'start' (a journal with results is an error), 'force' (start again over it),
   !> 'resume' (continue it; it must exist and have the same fingerprint) or 'auto' (resume
   !> when it holds results, else start). A stop signal (SIGTERM, SIGINT) ends the run after
   !> the tasks in hand with 128 + its number. An error of a task ends the run with it, the
   !> tasks before it journaled.
   subroutine run_tasks(tasks, ntasks, journal, fingerprint, mode, results, error)
      class(task_list), intent(inout) :: tasks
      integer, intent(in) :: ntasks
      character(len=*), intent(in) :: journal, fingerprint, mode
      type(task_text), allocatable, intent(out) :: results(:)
      type(error_type), allocatable, intent(out) :: error
      type(journal_file) :: out
      type(error_type), allocatable :: e
      character(len=:), allocatable :: text, message
      integer, allocatable :: stat(:), owner(:)
      type(task_deal) :: deal
      integer :: np, k, k0, k1, ndone, chunk
      allocate (results(ntasks))
      ndone = 0
      if (len(journal) > 0) then
         call out%open(journal, fingerprint, mode, error, most=ntasks)
         if (allocated(error)) return
         ndone = size(out%done)
         results(:ndone) = out%done
      end if
      call catch_stop_signals()
      np = n_ranks()
      chunk = np*tasks_per_share(ntasks - ndone, np)
      allocate (stat(ntasks), owner(ntasks))
      do k0 = ndone + 1, ntasks, chunk
         k1 = min(k0 + chunk - 1, ntasks)
         ! The chunk's tasks dealt to the ranks as they become free; after an error or a stop
         ! signal this rank takes no more
         message = ''
         stat(k0:k1) = stat_not_run
         call deal%open(k0, k1)
         do
            if (stop_signal() /= 0) exit
            k = deal%take()
            if (k == 0) exit
            call tasks%run(k, text, e)
            if (allocated(e)) then
               stat(k) = e%stat
               message = e%message
               exit
            end if
            stat(k) = 0
            results(k)%s = text
         end do
         call deal%close()
         ! Every rank learns who ran each task and receives every result of the chunk; rank 0
         ! journals them in order, up to the first that is missing
         owner(k0:k1) = ranks_that_ran(stat(k0:k1) /= stat_not_run)
         do k = k0, k1
            if (owner(k) >= 0 .and. np > 1) then
               call share_one(stat(k), owner(k))
               if (stat(k) == 0) then
                  if (.not. allocated(results(k)%s)) results(k)%s = ''
                  call share(results(k)%s, owner(k))
               else
                  if (this_rank() /= owner(k)) message = ''
                  call share(message, owner(k))
               end if
            end if
            if (stat(k) == 0 .and. .not. allocated(error)) then
               if (len(journal) > 0 .and. is_root()) call out%put(k, results(k)%s, e)
               if (allocated(e)) call move_alloc(e, error)
            else if (.not. allocated(error)) then
               if (stat(k) == stat_not_run) then
                  call fatal_error(error, 'stopped by a signal after '//str(k - 1)//' of '// &
                     str(ntasks)//' tasks; continue with --resume', 128 + max(stop_signal(), 15))
               else
                  call fatal_error(error, message, stat(k))
               end if
            end if
         end do
         if (allocated(error)) exit
         if (any_rank(stop_signal() /= 0) .and. k1 < ntasks) then
            call fatal_error(error, 'stopped by a signal after '//str(k1)//' of '// &
               str(ntasks)//' tasks; continue with --resume', 128 + max(stop_signal(), 15))
            exit
         end if
      end do
      call release_stop_signals()
      call out%close(e)
      if (allocated(e) .and. .not. allocated(error)) call move_alloc(e, error)
   contains
      subroutine share_one(value, from)
         integer, intent(inout) :: value
         integer, intent(in) :: from
         integer, allocatable :: buf(:)
         buf = [value]
         call share(buf, from)
         value = buf(1)
      end subroutine share_one
   end subroutine run_tasks

end module usharp_task_farm
