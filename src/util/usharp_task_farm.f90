!> Independent tasks (the repetitions of the self-check, the tests of a design) spread over the
!> MPI ranks, round robin in chunks (OpenMP threads inside each task), with their results kept
!> in a journal in the order of the tasks: every rank receives every result, rank 0 alone
!> writes, and a stopped run continues (--resume) on any number of ranks. A result is text
!> (numbers written at full precision), and the caller reads every result back from that text,
!> computed or replayed, so the outcome does not depend on the number of ranks or on a resume.
!>
!> The journal: a fingerprint line, then per task a line `task <k> <n>`, the n lines of its
!> result and a line `end <k>`; a block cut short by a kill is dropped when it is read.
module usharp_task_farm
   use usharp_error, only: error_type, fatal_error, stat_input, stat_usage
   use usharp_strings, only: str
   use usharp_filesys, only: raw_file, file_exists, read_line
   use usharp_signal, only: catch_stop_signals, release_stop_signals, stop_signal
   use usharp_mpi, only: n_ranks, this_rank, is_root, owner_of, share, any_rank, parallel_sync, &
                         tasks_per_share
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

   !> One task's result
   type :: task_text
      character(len=:), allocatable :: s
   end type task_text

   character(len=*), parameter :: fingerprint_tag = '# fingerprint '
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
      type(raw_file) :: out
      type(error_type), allocatable :: e
      type(task_text), allocatable :: done(:)
      character(len=:), allocatable :: old_fingerprint, text, message
      integer, allocatable :: stat(:)
      integer :: np, k, k0, k1, ndone, chunk
      logical :: resuming
      allocate (results(ntasks))
      ndone = 0
      if (len(journal) > 0) then
         resuming = mode == 'resume'
         if (mode == 'auto') resuming = has_results(journal)
         if (resuming) then
            call read_task_journal(journal, done, old_fingerprint, error)
            if (.not. allocated(error) .and. old_fingerprint /= fingerprint) &
               call fatal_error(error, journal//': cannot resume: the input changed since the '// &
                  'journal was written (start again with --force)', stat_input)
            if (.not. allocated(error) .and. size(done) > ntasks) &
               call fatal_error(error, journal//': cannot resume: it holds more tasks than this '// &
                  'run has', stat_input)
            if (allocated(error)) return
            ndone = size(done)
            results(:ndone) = done
         else if (mode /= 'force' .and. has_results(journal)) then
            call fatal_error(error, journal//': holds the journal of an earlier run; continue it '// &
               'with --resume, or start again and overwrite it with --force', stat_usage)
            return
         end if
         ! Every rank has read the journal before rank 0 writes it again
         call parallel_sync()
         if (is_root()) then
            call out%create(journal, error)
            if (.not. allocated(error)) call out%put(fingerprint_tag//fingerprint//new_line('a'), error)
            do k = 1, ndone
               if (.not. allocated(error)) call out%put(block(k, results(k)%s), error)
            end do
         end if
         if (any_rank(allocated(error))) then
            if (.not. allocated(error)) call fatal_error(error, journal//': rank 0 cannot write it')
            call out%close()
            return
         end if
      end if
      call catch_stop_signals()
      np = n_ranks()
      chunk = np*tasks_per_share(ntasks - ndone, np)
      allocate (stat(ntasks))
      do k0 = ndone + 1, ntasks, chunk
         k1 = min(k0 + chunk - 1, ntasks)
         ! This rank's tasks of the chunk (round robin), one after the other; after an error
         ! or a stop signal the rest are not run
         message = ''
         stat(k0:k1) = 0
         do k = k0 + this_rank(), k1, np
            stat(k) = stat_not_run
            if (k > k0 + this_rank()) then
               if (stat(k - np) /= 0) cycle
            end if
            if (stop_signal() /= 0) cycle
            call tasks%run(k, text, e)
            if (allocated(e)) then
               stat(k) = e%stat
               message = e%message
            else
               stat(k) = 0
               results(k)%s = text
            end if
         end do
         ! Every rank receives every result of the chunk; rank 0 journals them in order, up
         ! to the first that is missing
         do k = k0, k1
            associate (owner => owner_of(k, k0, np))
               if (n_ranks() > 1) then
                  call share_one(stat(k), owner)
                  if (stat(k) == 0) then
                     if (.not. allocated(results(k)%s)) results(k)%s = ''
                     call share(results(k)%s, owner)
                  else if (stat(k) /= stat_not_run) then
                     if (this_rank() /= owner) message = ''
                     call share(message, owner)
                  end if
               end if
               if (stat(k) == 0 .and. .not. allocated(error)) then
                  if (len(journal) > 0 .and. is_root()) call out%put(block(k, results(k)%s), e)
                  if (allocated(e)) call move_alloc(e, error)
               else if (.not. allocated(error)) then
                  if (stat(k) == stat_not_run) then
                     call fatal_error(error, 'stopped by a signal after '//str(k - 1)//' of '// &
                        str(ntasks)//' tasks; continue with --resume', 128 + max(stop_signal(), 15))
                  else
                     call fatal_error(error, message, stat(k))
                  end if
               end if
            end associate
         end do
         if (allocated(error)) exit
         if (any_rank(stop_signal() /= 0) .and. k1 < ntasks) then
            call fatal_error(error, 'stopped by a signal after '//str(k1)//' of '// &
               str(ntasks)//' tasks; continue with --resume', 128 + max(stop_signal(), 15))
            exit
         end if
      end do
      call release_stop_signals()
      if (len(journal) > 0 .and. is_root()) then
         call out%close(e)
         if (allocated(e) .and. .not. allocated(error)) call move_alloc(e, error)
      end if
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

   !> Task k's block in the journal
   pure function block(k, text) result(b)
      integer, intent(in) :: k
      character(len=*), intent(in) :: text
      character(len=:), allocatable :: b
      b = 'task '//str(k)//' '//str(count_lines(text))//new_line('a')//text//'end '//str(k)// &
          new_line('a')
   end function block

   pure integer function count_lines(text) result(n)
      character(len=*), intent(in) :: text
      integer :: i
      n = 0
      do i = 1, len(text)
         if (text(i:i) == new_line('a')) n = n + 1
      end do
   end function count_lines

   !> Whether a task journal holds a result
   logical function has_results(path)
      character(len=*), intent(in) :: path
      type(task_text), allocatable :: done(:)
      character(len=:), allocatable :: fp
      type(error_type), allocatable :: error
      has_results = .false.
      if (.not. file_exists(path)) return
      call read_task_journal(path, done, fp, error)
      has_results = .not. allocated(error) .and. size(done) > 0
   end function has_results

   !> The fingerprint and the whole results, in order, of a task journal
   subroutine read_task_journal(path, done, fingerprint, error)
      character(len=*), intent(in) :: path
      type(task_text), allocatable, intent(out) :: done(:)
      character(len=:), allocatable, intent(out) :: fingerprint
      type(error_type), allocatable, intent(out) :: error
      character(len=:), allocatable :: line, text
      integer :: unit, ios, k, n, j
      character(len=8) :: word
      allocate (done(0))
      fingerprint = ''
      if (.not. file_exists(path)) then
         call fatal_error(error, path//': no journal to resume from (start without --resume)', stat_input)
         return
      end if
      open (newunit=unit, file=path, status='old', action='read', iostat=ios)
      if (ios /= 0) then
         call fatal_error(error, path//': cannot read it', stat_input)
         return
      end if
      do
         call read_line(unit, line, ios)
         if (ios /= 0) exit
         if (index(line, fingerprint_tag) == 1) then
            fingerprint = line(len(fingerprint_tag) + 1:)
            cycle
         end if
         read (line, *, iostat=ios) word, k, n
         if (ios /= 0 .or. word /= 'task' .or. k /= size(done) + 1) exit
         text = ''
         do j = 1, n
            call read_line(unit, line, ios)
            if (ios /= 0) exit
            text = text//line//new_line('a')
         end do
         ! A block cut short by a kill is not a result
         if (ios /= 0) exit
         call read_line(unit, line, ios)
         if (ios /= 0 .or. line /= 'end '//str(k)) exit
         done = [done, task_text(text)]
      end do
      close (unit)
   end subroutine read_task_journal

end module usharp_task_farm
