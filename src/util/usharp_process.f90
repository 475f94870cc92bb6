!> Running another program: posix_spawn with an argument vector (no command string is
!> parsed by a shell on the way), in a folder, with stdin from /dev/null and stdout and
!> stderr into files, in a process group of its own, under a time limit. At the limit, or
!> when usharp is asked to stop (usharp_signal), the whole group gets SIGTERM and, after a
!> grace period, SIGKILL; when the program ends, whatever it left running in its group is
!> killed too. posix_spawn is safe to call from several threads at once (execute_command_line
!> goes through system(), which is not specified to be).
!>
!> Linux/glibc: the sizes of the opaque spawn structures and the flag values are those of
!> glibc on 64-bit Linux, with room to spare.
module usharp_process
   use, intrinsic :: iso_c_binding, only: c_int, c_short, c_char, c_ptr, c_null_ptr, &
                                          c_null_char, c_loc, c_int64_t, c_f_pointer, &
                                          c_associated
   use, intrinsic :: iso_fortran_env, only: int64
   use usharp_kinds, only: dp
   use usharp_signal, only: stop_signal
   implicit none
   private

   public :: process_result, run_process
   public :: proc_exited, proc_signalled, proc_timed_out, proc_stopped, proc_spawn_failed, &
             proc_status_lost

   !> How a program ended
   integer, parameter :: proc_exited = 0       !< by itself, code = exit status
   integer, parameter :: proc_signalled = 1    !< killed by a signal from elsewhere, code = signal
   integer, parameter :: proc_timed_out = 2    !< stopped at its time limit
   integer, parameter :: proc_stopped = 3      !< stopped because usharp received a stop signal
   integer, parameter :: proc_spawn_failed = 4 !< could not be started, code = errno
   integer, parameter :: proc_status_lost = 5  !< waitpid failed, code = errno; killed then

   type :: process_result
      integer :: how = proc_exited
      integer :: code = 0
   end type process_result

   integer(c_int), parameter :: sigterm = 15, sigkill = 9, wnohang = 1
   integer(c_int), parameter :: o_rdonly = 0, o_wronly = 1, o_creat = int(o'100', c_int), &
                                o_trunc = int(o'1000', c_int)
   integer(c_short), parameter :: spawn_setpgroup = 2_c_short

   !> Opaque posix_spawnattr_t (336 bytes) and posix_spawn_file_actions_t (80 bytes)
   type, bind(C) :: spawn_attr
      integer(c_int64_t) :: opaque(96) = 0
   end type spawn_attr
   type, bind(C) :: spawn_actions
      integer(c_int64_t) :: opaque(32) = 0
   end type spawn_actions

   interface
      function c_posix_spawn(pid, path, actions, attr, argv, envp) bind(C, name='posix_spawn') result(r)
         import :: c_int, c_char, c_ptr, spawn_attr, spawn_actions
         integer(c_int), intent(out) :: pid
         character(kind=c_char), intent(in) :: path(*)
         type(spawn_actions), intent(in) :: actions
         type(spawn_attr), intent(in) :: attr
         type(c_ptr), intent(in) :: argv(*)
         type(c_ptr), value, intent(in) :: envp
         integer(c_int) :: r
      end function c_posix_spawn
      function c_attr_init(attr) bind(C, name='posix_spawnattr_init') result(r)
         import :: c_int, spawn_attr
         type(spawn_attr), intent(inout) :: attr
         integer(c_int) :: r
      end function c_attr_init
      function c_attr_destroy(attr) bind(C, name='posix_spawnattr_destroy') result(r)
         import :: c_int, spawn_attr
         type(spawn_attr), intent(inout) :: attr
         integer(c_int) :: r
      end function c_attr_destroy
      function c_attr_setflags(attr, flags) bind(C, name='posix_spawnattr_setflags') result(r)
         import :: c_int, c_short, spawn_attr
         type(spawn_attr), intent(inout) :: attr
         integer(c_short), value, intent(in) :: flags
         integer(c_int) :: r
      end function c_attr_setflags
      function c_attr_setpgroup(attr, pgroup) bind(C, name='posix_spawnattr_setpgroup') result(r)
         import :: c_int, spawn_attr
         type(spawn_attr), intent(inout) :: attr
         integer(c_int), value, intent(in) :: pgroup
         integer(c_int) :: r
      end function c_attr_setpgroup
      function c_actions_init(fa) bind(C, name='posix_spawn_file_actions_init') result(r)
         import :: c_int, spawn_actions
         type(spawn_actions), intent(inout) :: fa
         integer(c_int) :: r
      end function c_actions_init
      function c_actions_destroy(fa) bind(C, name='posix_spawn_file_actions_destroy') result(r)
         import :: c_int, spawn_actions
         type(spawn_actions), intent(inout) :: fa
         integer(c_int) :: r
      end function c_actions_destroy
      function c_actions_addopen(fa, fd, path, flags, mode) &
         bind(C, name='posix_spawn_file_actions_addopen') result(r)
         import :: c_int, c_char, spawn_actions
         type(spawn_actions), intent(inout) :: fa
         integer(c_int), value, intent(in) :: fd, flags, mode
         character(kind=c_char), intent(in) :: path(*)
         integer(c_int) :: r
      end function c_actions_addopen
      function c_actions_addchdir(fa, path) bind(C, name='posix_spawn_file_actions_addchdir_np') result(r)
         import :: c_int, c_char, spawn_actions
         type(spawn_actions), intent(inout) :: fa
         character(kind=c_char), intent(in) :: path(*)
         integer(c_int) :: r
      end function c_actions_addchdir
      function c_waitpid(pid, status, options) bind(C, name='waitpid') result(r)
         import :: c_int
         integer(c_int), value, intent(in) :: pid, options
         integer(c_int), intent(out) :: status
         integer(c_int) :: r
      end function c_waitpid
      function c_kill(pid, sig) bind(C, name='kill') result(r)
         import :: c_int
         integer(c_int), value, intent(in) :: pid, sig
         integer(c_int) :: r
      end function c_kill
      !> The address of a symbol; with the handle RTLD_DEFAULT (null) the one the program uses
      function c_dlsym(handle, symbol) bind(C, name='dlsym') result(address)
         import :: c_ptr, c_char
         type(c_ptr), value, intent(in) :: handle
         character(kind=c_char), intent(in) :: symbol(*)
         type(c_ptr) :: address
      end function c_dlsym
      function c_usleep(usec) bind(C, name='usleep') result(r)
         import :: c_int
         integer(c_int), value, intent(in) :: usec
         integer(c_int) :: r
      end function c_usleep
      function c_errno_location() bind(C, name='__errno_location') result(p)
         import :: c_ptr
         type(c_ptr) :: p
      end function c_errno_location
   end interface

   !> A C string that stays in place while its address is used
   type :: c_string
      character(kind=c_char), allocatable :: chars(:)
   end type c_string

contains

   !> Run the program argv(1) (an absolute path) with the arguments argv(2:) in the folder
   !> dir, stdin from /dev/null, stdout and stderr into the files out and err of dir; wait
   !> until it ends, at most time_limit s (then TERM to its group, KILL grace s later).
   !> stoppable (default true): also stop it when usharp receives a stop signal.
   subroutine run_process(argv, dir, out, err, time_limit, grace, res, stoppable)
      character(len=*), intent(in) :: argv(:)
      character(len=*), intent(in) :: dir, out, err
      real(dp), intent(in) :: time_limit, grace
      type(process_result), intent(out) :: res
      logical, intent(in), optional :: stoppable
      type(c_string), allocatable, target :: args(:)
      type(c_ptr), allocatable :: ptrs(:)
      type(c_ptr), allocatable, target :: env_kept(:)
      type(c_ptr) :: envp
      type(spawn_attr) :: attr
      type(spawn_actions) :: fa
      integer(c_int) :: pid, rc, status, r
      integer(int64) :: t0, now, rate, t_term
      integer :: k, sleep_us
      logical :: terminating, may_stop
      integer(c_int), pointer :: errno

      may_stop = .true.
      if (present(stoppable)) may_stop = stoppable
      allocate (args(size(argv)), ptrs(size(argv) + 1))
      do k = 1, size(argv)
         args(k)%chars = to_c(trim(argv(k)))
         ptrs(k) = c_loc(args(k)%chars)
      end do
      ptrs(size(argv) + 1) = c_null_ptr
      rc = c_attr_init(attr)
      rc = c_attr_setflags(attr, spawn_setpgroup)
      rc = c_attr_setpgroup(attr, 0_c_int)
      rc = c_actions_init(fa)
      rc = c_actions_addchdir(fa, to_c(dir))
      rc = c_actions_addopen(fa, 0_c_int, to_c('/dev/null'), o_rdonly, 0_c_int)
      rc = c_actions_addopen(fa, 1_c_int, to_c(out), ior(ior(o_wronly, o_creat), o_trunc), &
                             int(o'644', c_int))
      rc = c_actions_addopen(fa, 2_c_int, to_c(err), ior(ior(o_wronly, o_creat), o_trunc), &
                             int(o'644', c_int))
      call environment(env_kept, envp)
      rc = c_posix_spawn(pid, to_c(trim(argv(1))), fa, attr, ptrs, envp)
      r = c_actions_destroy(fa)
      r = c_attr_destroy(attr)
      if (rc /= 0) then
         res%how = proc_spawn_failed
         res%code = int(rc)
         return
      end if

      call system_clock(t0, rate)
      terminating = .false.
      t_term = 0
      sleep_us = 2000
      do
         r = c_waitpid(pid, status, wnohang)
         if (r == pid) exit
         if (r < 0) then
            ! The status is lost (reaped elsewhere): report the program as failed, with why
            call c_f_pointer(c_errno_location(), errno)
            res%code = int(errno)
            r = c_kill(-pid, sigkill)
            res%how = proc_status_lost
            return
         end if
         call system_clock(now)
         if (.not. terminating) then
            if (may_stop .and. stop_signal() /= 0) then
               res%how = proc_stopped
            else if (real(now - t0, dp)/real(rate, dp) > time_limit) then
               res%how = proc_timed_out
            end if
            if (res%how /= proc_exited) then
               r = c_kill(-pid, sigterm)
               terminating = .true.
               t_term = now
            end if
         else if (real(now - t_term, dp)/real(rate, dp) > grace) then
            r = c_kill(-pid, sigkill)
         end if
         r = c_usleep(int(sleep_us, c_int))
         sleep_us = min(2*sleep_us, 50000)
      end do
      ! Whatever the program left running in its group goes with it (again after a moment:
      ! a member that was forking at the first kill may have escaped it)
      do k = 1, 5
         if (c_kill(-pid, sigkill) /= 0) exit
         r = c_usleep(5000_c_int)
      end do
      if (res%how /= proc_exited) return
      if (iand(status, 127_c_int) == 0) then
         res%code = int(iand(ishft(status, -8), 255_c_int))
      else
         res%how = proc_signalled
         res%code = int(iand(status, 127_c_int))
      end if
   end subroutine run_process

   !> The program's environment as it is now (C's environ), for the program it starts: an
   !> FE code needs its PATH, licence and scratch variables. A Fortran variable bound to the
   !> name environ would be a definition of its own, a null that shadows the C library's, and
   !> every program started would get an empty environment; so the C library's is looked up.
   !> Left out: the variables by which an MPI launcher tells a process its place in the job
   !> (launcher_variable). A program started from a rank would take them for its own: a usharp
   !> there tried to join the job, failed, and left the ranks waiting for it to the end.
   !> kept: the entries passed on (pointers into environ), null-terminated; envp points at them
   subroutine environment(kept, envp)
      type(c_ptr), allocatable, target, intent(out) :: kept(:)
      type(c_ptr), intent(out) :: envp
      type(c_ptr), pointer :: environ
      type(c_ptr), pointer :: entries(:)
      type(c_ptr) :: address
      character(kind=c_char), pointer :: chars(:)
      integer :: n, k, m
      envp = c_null_ptr
      allocate (kept(1))
      kept(1) = c_null_ptr
      address = c_dlsym(c_null_ptr, 'environ'//c_null_char)
      ! (the C library always defines it; were it not found, the program would start with an
      ! empty environment, as with envp null)
      if (.not. c_associated(address)) return
      call c_f_pointer(address, environ)
      if (.not. c_associated(environ)) return
      ! The entries up to the null that ends them
      n = 0
      do
         call c_f_pointer(environ, entries, [n + 1])
         if (.not. c_associated(entries(n + 1))) exit
         n = n + 1
      end do
      deallocate (kept)
      allocate (kept(n + 1))
      m = 0
      do k = 1, n
         ! The name: at most 32 characters are needed to know it
         call c_f_pointer(entries(k), chars, [32])
         if (launcher_variable(chars)) cycle
         m = m + 1
         kept(m) = entries(k)
      end do
      kept(m + 1) = c_null_ptr
      envp = c_loc(kept(1))
   end subroutine environment

   !> Whether an environment entry (NAME=value, null-terminated; only its first characters
   !> read) is one an MPI launcher sets to place a process in its job: Open MPI's (OMPI_,
   !> OPAL_, PRTE_), PMI's and PMIx's (SLURM's srun, Hydra), MPICH's local rank counts
   pure logical function launcher_variable(chars) result(yes)
      character(kind=c_char), intent(in) :: chars(:)
      character(len=*), parameter :: prefixes(8) = [character(len=16) :: 'OMPI_', 'OPAL_', &
         'PRTE_', 'PMIX_', 'PMI_', 'HYDRA_', 'MPI_LOCALNRANKS=', 'MPI_LOCALRANKID=']
      character(len=16) :: head
      integer :: k
      head = ''
      do k = 1, min(16, size(chars))
         if (chars(k) == c_null_char) exit
         head(k:k) = chars(k)
      end do
      yes = .false.
      do k = 1, size(prefixes)
         if (head(:len_trim(prefixes(k))) == trim(prefixes(k))) yes = .true.
      end do
   end function launcher_variable

   pure function to_c(text) result(chars)
      character(len=*), intent(in) :: text
      character(kind=c_char), allocatable :: chars(:)
      integer :: k
      allocate (chars(len(text) + 1))
      do k = 1, len(text)
         chars(k) = text(k:k)
      end do
      chars(len(text) + 1) = c_null_char
   end function to_c
end module usharp_process
