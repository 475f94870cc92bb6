!> The one place that speaks MPI (the mpi_f08 module): start and stop, this process's rank and
!> the number of ranks, and the broadcasts with which independent results computed on the
!> ranks are shared so that every rank (and rank 0, which writes the files) holds them in one
!> fixed order; the deal that hands independent tasks to the ranks as they become free, and
!> pairs the ranks out of tasks, as helpers, with those still at work; the blocks of a batch
!> of points that ranks in lockstep split among them. A program started
!> without an MPI launcher (mpirun, srun) does not start MPI at all: it is a single rank and
!> every procedure here makes no MPI call.
module usharp_mpi
   use mpi_f08, only: MPI_Init_thread, MPI_Initialized, MPI_Finalized, MPI_Finalize, MPI_Comm_rank, &
                      MPI_Comm_size, MPI_Bcast, MPI_Allreduce, MPI_Abort, MPI_Barrier, &
                      MPI_Get_library_version, MPI_MAX_LIBRARY_VERSION_STRING, MPI_COMM_WORLD, MPI_INTEGER, &
                      MPI_Isend, MPI_Irecv, MPI_Recv, MPI_Iprobe, MPI_Probe, MPI_Get_count, MPI_Testall, &
                      MPI_Waitall, MPI_Request, MPI_Status, MPI_ANY_SOURCE, MPI_STATUS_IGNORE, &
                      MPI_STATUSES_IGNORE, &
                      MPI_DOUBLE_PRECISION, MPI_CHARACTER, MPI_LOGICAL, MPI_LOR, MPI_SUM, &
                      MPI_THREAD_FUNNELED, MPI_MAX, MPI_Win, MPI_Win_allocate, MPI_Win_free, &
                      MPI_Win_lock_all, MPI_Win_unlock_all, MPI_Win_lock, MPI_Win_unlock, MPI_Put, &
                      MPI_Fetch_and_op, MPI_Win_flush, MPI_LOCK_EXCLUSIVE, MPI_INFO_NULL, MPI_ADDRESS_KIND, &
                      MPI_Send, MPI_Compare_and_swap, MPI_Get_accumulate, MPI_NO_OP, MPI_REPLACE, MPI_Datatype
   use, intrinsic :: iso_c_binding, only: c_ptr
   use usharp_kinds, only: dp
   use usharp_strings, only: str
   implicit none
   private

   public :: parallel_start, parallel_stop, parallel_abort, this_rank, n_ranks, is_root, owner_of
   public :: share, any_rank, parallel_sync, parallel_description, tasks_per_share, sum_over_ranks
   public :: task_deal, ranks_that_ran, block_of, share_blocks
   public :: transfer_set, post_send, post_receive, header_waiting, receive_header
   public :: send_packet, receive_packet, counts_of_ranks

   !> Tasks first to last handed out one at a time to whichever rank asks first (a rank asks
   !> when it is free, so unequal tasks even out): a counter on rank 0 that every rank
   !> fetches and increments atomically (MPI one-sided, passive target), or a plain counter
   !> when there is one rank.
   !>
   !> A rank out of tasks may offer itself as a helper to the ranks still at work: a rank at
   !> work claims free helpers (claim) and hands each a block of a batch of independent
   !> points (send_packet to it, receive_packet of its results), keeping them until its task
   !> ends (release). The claims sit beside the counter on rank 0, one per rank, changed
   !> atomically: free, not offered, or the rank that holds it. The last rank to run out of
   !> tasks sends every other rank the stop (see offer, await).
   type :: task_deal
      private
      integer :: next = 0, last = 0
      logical :: shared = .false.
      !> This rank took the last task, or found none left: every task has been dealt
      logical :: dealt = .false.
      type(MPI_Win) :: win
      integer, allocatable :: helpers(:)  !< the ranks this rank holds
   contains
      procedure :: open => deal_open
      procedure :: take => deal_take
      procedure :: close => deal_close
      procedure :: claim => deal_claim
      procedure :: release => deal_release
      procedure :: helper_ranks => deal_helper_ranks
      procedure :: all_dealt => deal_all_dealt
      procedure :: offer => deal_offer
      procedure :: await => deal_await
   end type task_deal

   ! The deal's window on rank 0: the next task, the ranks out of tasks, then each rank's claim
   integer, parameter :: slot_next = 0, slot_out = 1, slot_claim = 2
   integer, parameter :: claim_not_offered = -1, claim_free = -2
   ! The tag of the work a rank hands its helpers (and of the stop), and of their results
   integer, parameter, public :: tag_help = 81, tag_help_result = 82

   !> Non-blocking transfers in flight between a rank and rank 0 (a stream of results that
   !> rank 0 takes as they come while the ranks work on): their buffers must stay in place,
   !> unchanged, until done or wait says they are complete
   type :: transfer_set
      private
      type(MPI_Request), allocatable :: req(:)
   contains
      procedure :: done => transfers_done
      procedure :: wait => transfers_wait
   end type transfer_set

   !> Start sending an array to rank 0 with a tag (see transfer_set)
   interface post_send
      module procedure post_send_ints, post_send_reals, post_send_text
   end interface post_send

   !> Start receiving an array of known size from a rank with a tag (see transfer_set)
   interface post_receive
      module procedure post_receive_reals, post_receive_text
   end interface post_receive

   !> Every rank sends its block of a batch's columns to all (see block_of)
   interface share_blocks
      module procedure share_blocks_reals, share_blocks_matrix, share_blocks_ints, share_blocks_text
   end interface share_blocks

   !> Broadcast from one rank to all: the receivers' arrays take the sender's size
   interface share
      module procedure share_ints, share_reals, share_text
   end interface share

contains

   !> Start MPI when the process was launched by an MPI launcher (its environment says so);
   !> OpenMP threads inside a rank do not call MPI (funneled)
   subroutine parallel_start()
      logical :: started
      integer :: provided
      if (.not. launched()) return
      call MPI_Initialized(started)
      if (.not. started) call MPI_Init_thread(MPI_THREAD_FUNNELED, provided)
   end subroutine parallel_start

   !> Stop MPI (before the process exits, on every rank)
   subroutine parallel_stop()
      if (.not. running()) return
      call MPI_Finalize()
   end subroutine parallel_stop

   !> End every rank at once with an exit code (a rank that cannot go on)
   subroutine parallel_abort(code)
      integer, intent(in) :: code
      if (.not. running()) return
      call MPI_Abort(MPI_COMM_WORLD, code)
   end subroutine parallel_abort

   !> Whether the environment names an MPI launcher (Open MPI's mpirun, Hydra, PMI, PMIx: SLURM's srun)
   logical function launched()
      character(len=*), parameter :: names(5) = [character(len=20) :: 'OMPI_COMM_WORLD_SIZE', &
         'PMI_SIZE', 'PMIX_RANK', 'PMI_RANK', 'MPI_LOCALNRANKS']
      integer :: i, length, status
      launched = .false.
      do i = 1, size(names)
         call get_environment_variable(trim(names(i)), length=length, status=status)
         if (status == 0) launched = .true.
      end do
   end function launched

   logical function running()
      logical :: started, finished
      call MPI_Initialized(started)
      running = started
      if (.not. started) return
      call MPI_Finalized(finished)
      running = .not. finished
   end function running

   !> This process's rank, 0 to n_ranks() - 1
   integer function this_rank() result(r)
      r = 0
      if (running()) call MPI_Comm_rank(MPI_COMM_WORLD, r)
   end function this_rank

   !> The number of ranks (1 without MPI)
   integer function n_ranks() result(n)
      n = 1
      if (running()) call MPI_Comm_size(MPI_COMM_WORLD, n)
   end function n_ranks

   !> Whether this is rank 0, the one that writes files and prints
   logical function is_root()
      is_root = this_rank() == 0
   end function is_root

   !> The rank that does task k of a list, the i-th task of the list counted from first:
   !> round robin, so consecutive tasks run at the same time
   pure integer function owner_of(k, first, nranks) result(r)
      integer, intent(in) :: k, first, nranks
      r = modulo(k - first, nranks)
   end function owner_of

   !> The MPI library and this process's place: 'Open MPI v4.1.4, rank 0 of 2', or the library
   !> and 'not started' for a program started without a launcher
   function parallel_description() result(text)
      character(len=:), allocatable :: text
      character(len=MPI_MAX_LIBRARY_VERSION_STRING) :: version
      integer :: length, cut
      call MPI_Get_library_version(version, length)
      cut = scan(version(:length), ','//new_line('a'))
      if (cut > 1) length = cut - 1
      text = version(:length)
      if (running()) then
         text = text//', rank '//str(this_rank())//' of '//str(n_ranks())
      else
         text = text//', not started (one process: start ranks with mpirun or srun)'
      end if
   end function parallel_description

   !> Wait until every rank is here
   subroutine parallel_sync()
      if (running()) call MPI_Barrier(MPI_COMM_WORLD)
   end subroutine parallel_sync

   !> How many of ntasks independent tasks each of nranks ranks runs, on average, before the
   !> results are shared (and journaled): all of them, so that the ranks wait for each other
   !> once, but at most 8, so that a run killed outright loses little (with the tasks dealt
   !> as ranks become free, the wait at a chunk's end is about one task)
   pure integer function tasks_per_share(ntasks, nranks) result(c)
      integer, intent(in) :: ntasks, nranks
      c = max(1, min((ntasks + nranks - 1)/nranks, 8))
   end function tasks_per_share

   !> Start dealing tasks first to last (every rank must call it, unless alone)
   subroutine deal_open(self, first, last, alone)
      class(task_deal), intent(inout) :: self
      integer, intent(in) :: first, last
      !> This rank takes every task itself (no MPI call; the others do not take part)
      logical, intent(in), optional :: alone
      integer(MPI_ADDRESS_KIND) :: bytes
      type(c_ptr) :: base
      integer, allocatable :: start(:)
      self%next = first
      self%last = last
      self%dealt = first > last
      self%helpers = [integer ::]
      self%shared = running()
      if (present(alone)) self%shared = self%shared .and. .not. alone
      if (.not. self%shared) return
      if (n_ranks() == 1) then
         self%shared = .false.
         return
      end if
      allocate (start(slot_claim + n_ranks()))
      bytes = 0
      if (is_root()) bytes = storage_size(start)/8*size(start)
      call MPI_Win_allocate(bytes, storage_size(start)/8, MPI_INFO_NULL, MPI_COMM_WORLD, base, self%win)
      if (is_root()) then
         start = claim_not_offered
         start(slot_next + 1) = first
         start(slot_out + 1) = 0
         call MPI_Win_lock(MPI_LOCK_EXCLUSIVE, 0, 0, self%win)
         call MPI_Put(start, size(start), MPI_INTEGER, 0, 0_MPI_ADDRESS_KIND, size(start), MPI_INTEGER, &
                      self%win)
         call MPI_Win_unlock(0, self%win)
      end if
      ! No rank takes a task before the counter holds first
      call MPI_Barrier(MPI_COMM_WORLD)
      call MPI_Win_lock_all(0, self%win)
   end subroutine deal_open

   !> The next task for this rank, or 0 when all are taken
   integer function deal_take(self) result(k)
      class(task_deal), intent(inout) :: self
      if (self%shared) then
         k = fetch_add(self, slot_next, 1)
      else
         k = self%next
         self%next = self%next + 1
      end if
      if (k > self%last) k = 0
      self%dealt = k == 0 .or. k == self%last
   end function deal_take

   !> Whether this rank knows every task to have been dealt (it took the last, or found
   !> none left): only then may a rank out of tasks be free to help, so that a rank need not
   !> ask rank 0 before every batch
   pure logical function deal_all_dealt(self) result(yes)
      class(task_deal), intent(in) :: self
      yes = self%dealt
   end function deal_all_dealt

   !> Stop dealing (every rank that opened it shared must call it, after its last task and,
   !> where it offered itself, after await said stop)
   subroutine deal_close(self)
      class(task_deal), intent(inout) :: self
      if (.not. self%shared) return
      call MPI_Win_unlock_all(self%win)
      call MPI_Win_free(self%win)
      self%shared = .false.
   end subroutine deal_close

   !> Claim free helpers until this rank holds want of them (or none is free); a rank at
   !> work calls it before a batch it could share
   subroutine deal_claim(self, want)
      class(task_deal), intent(inout) :: self
      integer, intent(in) :: want
      integer, allocatable :: state(:)
      integer :: r, old, nothing(1)
      if (.not. self%shared .or. size(self%helpers) >= want) return
      allocate (state(1 + n_ranks()))
      ! One atomic read of the count out of tasks and of the claims: none out, none free
      nothing = 0
      call MPI_Get_accumulate(nothing, 0, MPI_INTEGER, state, size(state), MPI_INTEGER, 0, &
                              int(slot_out, MPI_ADDRESS_KIND), size(state), MPI_INTEGER, MPI_NO_OP, self%win)
      call MPI_Win_flush(0, self%win)
      if (state(1) == 0) return
      do r = 0, n_ranks() - 1
         if (size(self%helpers) >= want) exit
         if (state(2 + r) /= claim_free) cycle
         call MPI_Compare_and_swap(this_rank(), claim_free, old, MPI_INTEGER, 0, &
                                   int(slot_claim + r, MPI_ADDRESS_KIND), self%win)
         call MPI_Win_flush(0, self%win)
         if (old == claim_free) self%helpers = [self%helpers, r]
      end do
   end subroutine deal_claim

   !> Free the helpers this rank holds (at the end of its task: another rank may need them)
   subroutine deal_release(self)
      class(task_deal), intent(inout) :: self
      integer :: k
      if (.not. self%shared) return
      do k = 1, size(self%helpers)
         call put_atomic(self, slot_claim + self%helpers(k), claim_free)
      end do
      self%helpers = [integer ::]
   end subroutine deal_release

   !> The ranks this rank holds as helpers, in the order claimed
   pure function deal_helper_ranks(self) result(ranks)
      class(task_deal), intent(in) :: self
      integer, allocatable :: ranks(:)
      ranks = self%helpers
   end function deal_helper_ranks

   !> This rank is out of tasks: free its helpers and offer itself as one. False when it was
   !> the last rank at work (it has sent every other rank the stop and helps no one): else
   !> it serves work (await) until the stop comes
   logical function deal_offer(self) result(serving)
      class(task_deal), intent(inout) :: self
      integer :: r
      serving = .false.
      if (.not. self%shared) return
      call self%release()
      call put_atomic(self, slot_claim + this_rank(), claim_free)
      if (fetch_add(self, slot_out, 1) + 1 < n_ranks()) then
         serving = .true.
         return
      end if
      ! Every rank is out of tasks and no rank holds a helper: nothing else is in flight
      do r = 0, n_ranks() - 1
         if (r /= this_rank()) call send_packet(r, tag_help, [0], [real(dp) ::], '')
      end do
   end function deal_offer

   !> A helper's next work: its packet (ints(1) > 0) and the rank to send the results to;
   !> false at the stop
   logical function deal_await(self, owner, ints, reals, text) result(working)
      class(task_deal), intent(inout) :: self
      integer, intent(out) :: owner
      integer, allocatable, intent(out) :: ints(:)
      real(dp), allocatable, intent(out) :: reals(:)
      character(len=:), allocatable, intent(out) :: text
      owner = -1
      call receive_packet(owner, tag_help, ints, reals, text)
      working = self%shared .and. ints(1) > 0
   end function deal_await

   !> Atomically add inc to a slot of the deal's window; the value before
   integer function fetch_add(self, slot, inc) result(before)
      class(task_deal), intent(inout) :: self
      integer, intent(in) :: slot, inc
      call MPI_Fetch_and_op(inc, before, MPI_INTEGER, 0, int(slot, MPI_ADDRESS_KIND), MPI_SUM, self%win)
      call MPI_Win_flush(0, self%win)
   end function fetch_add

   !> Atomically set a slot of the deal's window
   subroutine put_atomic(self, slot, value)
      class(task_deal), intent(inout) :: self
      integer, intent(in) :: slot, value
      integer :: old
      call MPI_Fetch_and_op(value, old, MPI_INTEGER, 0, int(slot, MPI_ADDRESS_KIND), MPI_REPLACE, self%win)
      call MPI_Win_flush(0, self%win)
   end subroutine put_atomic

   !> Send a packet (integers, reals, text: three messages with one tag) to a rank; blocking
   subroutine send_packet(to, tag, ints, reals, text)
      integer, intent(in) :: to, tag
      integer, intent(in) :: ints(:)
      real(dp), intent(in) :: reals(:)
      character(len=*), intent(in) :: text
      call MPI_Send(ints, size(ints), MPI_INTEGER, to, tag, MPI_COMM_WORLD)
      call MPI_Send(reals, size(reals), MPI_DOUBLE_PRECISION, to, tag, MPI_COMM_WORLD)
      call MPI_Send(text, len(text), MPI_CHARACTER, to, tag, MPI_COMM_WORLD)
   end subroutine send_packet

   !> Receive a packet (see send_packet) from a rank, or from any rank when from < 0 (from is
   !> then the sender); blocking. The messages from one sender with one tag arrive in order.
   subroutine receive_packet(from, tag, ints, reals, text)
      integer, intent(inout) :: from
      integer, intent(in) :: tag
      integer, allocatable, intent(out) :: ints(:)
      real(dp), allocatable, intent(out) :: reals(:)
      character(len=:), allocatable, intent(out) :: text
      type(MPI_Status) :: status
      integer :: n
      if (from < 0) then
         call MPI_Probe(MPI_ANY_SOURCE, tag, MPI_COMM_WORLD, status)
         from = status%MPI_SOURCE
      end if
      allocate (ints(waiting(MPI_INTEGER)))
      call MPI_Recv(ints, size(ints), MPI_INTEGER, from, tag, MPI_COMM_WORLD, MPI_STATUS_IGNORE)
      allocate (reals(waiting(MPI_DOUBLE_PRECISION)))
      call MPI_Recv(reals, size(reals), MPI_DOUBLE_PRECISION, from, tag, MPI_COMM_WORLD, MPI_STATUS_IGNORE)
      n = waiting(MPI_CHARACTER)
      allocate (character(len=n) :: text)
      call MPI_Recv(text, len(text), MPI_CHARACTER, from, tag, MPI_COMM_WORLD, MPI_STATUS_IGNORE)

   contains

      !> The length of the next message from the sender with the tag, in items of type kind
      integer function waiting(kind) result(n)
         type(MPI_Datatype), intent(in) :: kind
         call MPI_Probe(from, tag, MPI_COMM_WORLD, status)
         call MPI_Get_count(status, kind, n)
      end function waiting
   end subroutine receive_packet

   !> The rank that ran each task, from each rank's own list of which it ran (-1: none
   !> did); every rank must call it
   function ranks_that_ran(ran) result(owner)
      logical, intent(in) :: ran(:)
      integer :: owner(size(ran)), mine(size(ran))
      mine = merge(this_rank(), -1, ran)
      owner = mine
      if (running() .and. size(ran) > 0) &
         call MPI_Allreduce(mine, owner, size(ran), MPI_INTEGER, MPI_MAX, MPI_COMM_WORLD)
   end function ranks_that_ran

   !> The block lo:hi of n points that rank r of nranks computes when ranks in lockstep split
   !> a batch: consecutive, the first n mod nranks ranks one point more (lo > hi: none)
   pure subroutine block_of(n, r, nranks, lo, hi)
      integer, intent(in) :: n, r, nranks
      integer, intent(out) :: lo, hi
      integer :: base, extra
      base = n/nranks
      extra = mod(n, nranks)
      lo = r*base + min(r, extra) + 1
      hi = lo + base - 1
      if (r < extra) hi = hi + 1
   end subroutine block_of

   subroutine share_blocks_reals(a)
      real(dp), intent(inout) :: a(:)
      integer :: r, lo, hi
      if (.not. running()) return
      do r = 0, n_ranks() - 1
         call block_of(size(a), r, n_ranks(), lo, hi)
         if (hi >= lo) call MPI_Bcast(a(lo:hi), hi - lo + 1, MPI_DOUBLE_PRECISION, r, MPI_COMM_WORLD)
      end do
   end subroutine share_blocks_reals

   subroutine share_blocks_matrix(a)
      real(dp), intent(inout) :: a(:, :)
      integer :: r, lo, hi
      if (.not. running()) return
      do r = 0, n_ranks() - 1
         call block_of(size(a, 2), r, n_ranks(), lo, hi)
         if (hi >= lo) call MPI_Bcast(a(:, lo:hi), size(a, 1)*(hi - lo + 1), MPI_DOUBLE_PRECISION, r, &
                                      MPI_COMM_WORLD)
      end do
   end subroutine share_blocks_matrix

   subroutine share_blocks_ints(a)
      integer, intent(inout) :: a(:)
      integer :: r, lo, hi
      if (.not. running()) return
      do r = 0, n_ranks() - 1
         call block_of(size(a), r, n_ranks(), lo, hi)
         if (hi >= lo) call MPI_Bcast(a(lo:hi), hi - lo + 1, MPI_INTEGER, r, MPI_COMM_WORLD)
      end do
   end subroutine share_blocks_ints

   subroutine share_blocks_text(a)
      character(len=*), intent(inout) :: a(:)
      integer :: r, lo, hi
      if (.not. running()) return
      do r = 0, n_ranks() - 1
         call block_of(size(a), r, n_ranks(), lo, hi)
         if (hi >= lo) call MPI_Bcast(a(lo:hi), len(a)*(hi - lo + 1), MPI_CHARACTER, r, MPI_COMM_WORLD)
      end do
   end subroutine share_blocks_text

   !> The sum of n over the ranks (every rank must call it)
   integer function sum_over_ranks(n) result(total)
      integer, intent(in) :: n
      total = n
      if (running()) call MPI_Allreduce(n, total, 1, MPI_INTEGER, MPI_SUM, MPI_COMM_WORLD)
   end function sum_over_ranks

   !> Each rank's n, in the order of the ranks (every rank must call it)
   function counts_of_ranks(n) result(counts)
      integer, intent(in) :: n
      integer, allocatable :: counts(:)
      integer, allocatable :: mine(:)
      allocate (mine(n_ranks()))
      mine = 0
      mine(this_rank() + 1) = n
      counts = mine
      if (running()) call MPI_Allreduce(mine, counts, size(mine), MPI_INTEGER, MPI_SUM, MPI_COMM_WORLD)
   end function counts_of_ranks

   !> Whether flag is true on any rank (every rank must call it)
   logical function any_rank(flag) result(any_true)
      logical, intent(in) :: flag
      any_true = flag
      if (running()) call MPI_Allreduce(flag, any_true, 1, MPI_LOGICAL, MPI_LOR, MPI_COMM_WORLD)
   end function any_rank

   subroutine share_ints(a, from)
      integer, allocatable, intent(inout) :: a(:)
      integer, intent(in) :: from
      integer :: n
      if (.not. running()) return
      if (this_rank() == from) n = size(a)
      if (receive_size(n, from)) then
         if (allocated(a)) deallocate (a)
         allocate (a(n))
      end if
      if (n > 0) call MPI_Bcast(a, n, MPI_INTEGER, from, MPI_COMM_WORLD)
   end subroutine share_ints

   subroutine share_reals(a, from)
      real(dp), allocatable, intent(inout) :: a(:)
      integer, intent(in) :: from
      integer :: n
      if (.not. running()) return
      if (this_rank() == from) n = size(a)
      if (receive_size(n, from)) then
         if (allocated(a)) deallocate (a)
         allocate (a(n))
      end if
      if (n > 0) call MPI_Bcast(a, n, MPI_DOUBLE_PRECISION, from, MPI_COMM_WORLD)
   end subroutine share_reals

   subroutine share_text(s, from)
      character(len=:), allocatable, intent(inout) :: s
      integer, intent(in) :: from
      integer :: n
      if (.not. running()) return
      if (this_rank() == from) n = len(s)
      if (receive_size(n, from)) then
         if (allocated(s)) deallocate (s)
         allocate (character(len=n) :: s)
      end if
      if (n > 0) call MPI_Bcast(s, n, MPI_CHARACTER, from, MPI_COMM_WORLD)
   end subroutine share_text

   subroutine post_send_ints(buf, tag, set)
      integer, intent(in), asynchronous :: buf(:)
      integer, intent(in) :: tag
      type(transfer_set), intent(inout) :: set
      type(MPI_Request) :: req
      call MPI_Isend(buf, size(buf), MPI_INTEGER, 0, tag, MPI_COMM_WORLD, req)
      call add_request(set, req)
   end subroutine post_send_ints

   subroutine post_send_reals(buf, tag, set)
      real(dp), intent(in), asynchronous :: buf(:)
      integer, intent(in) :: tag
      type(transfer_set), intent(inout) :: set
      type(MPI_Request) :: req
      call MPI_Isend(buf, size(buf), MPI_DOUBLE_PRECISION, 0, tag, MPI_COMM_WORLD, req)
      call add_request(set, req)
   end subroutine post_send_reals

   subroutine post_send_text(buf, tag, set)
      character(len=*), intent(in), asynchronous :: buf
      integer, intent(in) :: tag
      type(transfer_set), intent(inout) :: set
      type(MPI_Request) :: req
      call MPI_Isend(buf, len(buf), MPI_CHARACTER, 0, tag, MPI_COMM_WORLD, req)
      call add_request(set, req)
   end subroutine post_send_text

   subroutine post_receive_reals(buf, from, tag, set)
      real(dp), intent(inout), asynchronous :: buf(:)
      integer, intent(in) :: from, tag
      type(transfer_set), intent(inout) :: set
      type(MPI_Request) :: req
      call MPI_Irecv(buf, size(buf), MPI_DOUBLE_PRECISION, from, tag, MPI_COMM_WORLD, req)
      call add_request(set, req)
   end subroutine post_receive_reals

   subroutine post_receive_text(buf, from, tag, set)
      character(len=*), intent(inout), asynchronous :: buf
      integer, intent(in) :: from, tag
      type(transfer_set), intent(inout) :: set
      type(MPI_Request) :: req
      call MPI_Irecv(buf, len(buf), MPI_CHARACTER, from, tag, MPI_COMM_WORLD, req)
      call add_request(set, req)
   end subroutine post_receive_text

   subroutine add_request(set, req)
      type(transfer_set), intent(inout) :: set
      type(MPI_Request), intent(in) :: req
      if (.not. allocated(set%req)) allocate (set%req(0))
      set%req = [set%req, req]
   end subroutine add_request

   !> Whether every transfer of the set is complete (then the set is empty again)
   logical function transfers_done(self) result(done)
      class(transfer_set), intent(inout) :: self
      done = .true.
      if (.not. allocated(self%req)) return
      if (size(self%req) == 0) return
      call MPI_Testall(size(self%req), self%req, done, MPI_STATUSES_IGNORE)
      if (done) deallocate (self%req)
   end function transfers_done

   !> Wait until every transfer of the set is complete
   subroutine transfers_wait(self)
      class(transfer_set), intent(inout) :: self
      if (.not. allocated(self%req)) return
      if (size(self%req) > 0) call MPI_Waitall(size(self%req), self%req, MPI_STATUSES_IGNORE)
      deallocate (self%req)
   end subroutine transfers_wait

   !> Whether a message of integers with the tag waits from any rank (wait: until one does);
   !> its sender and length
   logical function header_waiting(tag, wait, from, n) result(found)
      integer, intent(in) :: tag
      logical, intent(in) :: wait
      integer, intent(out) :: from, n
      type(MPI_Status) :: status
      integer :: k
      found = .true.
      if (wait) then
         call MPI_Probe(MPI_ANY_SOURCE, tag, MPI_COMM_WORLD, status)
      else
         ! A probe moves the library's progress on: a message that has come may be seen only
         ! by the next one
         do k = 1, 4
            call MPI_Iprobe(MPI_ANY_SOURCE, tag, MPI_COMM_WORLD, found, status)
            if (found) exit
         end do
      end if
      from = -1
      n = 0
      if (.not. found) return
      from = status%MPI_SOURCE
      call MPI_Get_count(status, MPI_INTEGER, n)
   end function header_waiting

   !> Receive the n integers header_waiting found
   subroutine receive_header(buf, from, tag)
      integer, intent(out) :: buf(:)
      integer, intent(in) :: from, tag
      call MPI_Recv(buf, size(buf), MPI_INTEGER, from, tag, MPI_COMM_WORLD, MPI_STATUS_IGNORE)
   end subroutine receive_header

   !> Broadcast a size n from rank from; whether this rank is a receiver (which then makes
   !> room for the data that follow)
   logical function receive_size(n, from) result(receiving)
      integer, intent(inout) :: n
      integer, intent(in) :: from
      call MPI_Bcast(n, 1, MPI_INTEGER, from, MPI_COMM_WORLD)
      receiving = this_rank() /= from
   end function receive_size
end module usharp_mpi
