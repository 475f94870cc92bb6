!> Nothing a user made is overwritten unasked. Before a command writes, each file of its
!> output names that is already there must be the command's own earlier output, known by its
!> first line; any other file, and any file under the temporary name a result is written
!> through (<name>.part), is refused (a usage error naming it) unless --force is given.
!> A file without text lines (a plot) is known instead by its hash, which usharp records on a
!> line of a text file of its own beside it (see drawn_line).
module usharp_overwrite
   use, intrinsic :: iso_fortran_env, only: int64
   use usharp_error, only: error_type, fatal_error, stat_usage, stat_busy
   use usharp_filesys, only: file_exists, read_line, join_path, file_hash, hash_hex, make_dir, lock_file
   use usharp_mpi, only: is_root, share
   implicit none
   private

   public :: check_overwrite, check_overwrite_each, made_by_usharp, begins_like, simulate_mark
   public :: drawn_line, check_temporary_names, take_folder

   !> How the first line of a <test>.sim.txt that `usharp simulate` wrote begins ('*': the
   !> version)
   character(len=*), parameter :: simulate_mark = "# usharp * simulation of test '"

contains

   !> Make the output folder dir and hold its lock file (.usharp.lock) for the command, so that
   !> a second usharp writing into it (a job started twice, a requeued job beside its first
   !> start) is refused, stat_busy (exit 6), instead of both writing the same files. lock: the
   !> descriptor to release with unlock_file (-1 on the ranks but 0). Under MPI rank 0 takes
   !> the folder and every rank learns whether it could, so that none goes on to wait for a
   !> rank that stopped here; alone: rank 0 comes here alone (nothing shared).
   subroutine take_folder(dir, lock, error, alone)
      character(len=*), intent(in) :: dir
      integer, intent(out) :: lock
      type(error_type), allocatable, intent(out) :: error
      logical, intent(in), optional :: alone
      integer, allocatable :: code(:)
      lock = -1
      code = [0]
      if (is_root()) then
         call make_dir(dir, error)
         if (.not. allocated(error)) call lock_file(join_path(dir, '.usharp.lock'), lock, error)
         if (.not. allocated(error) .and. lock < 0) &
            call fatal_error(error, dir//': another usharp is writing into this folder (it holds '// &
               join_path(dir, '.usharp.lock')//'); wait for it or give another -o', stat_busy)
         if (allocated(error)) code = [error%stat]
      end if
      if (present(alone)) then
         if (alone) return
      end if
      call share(code, 0)
      if (code(1) /= 0 .and. .not. is_root()) call fatal_error(error, 'rank 0 could not take the '// &
         'output folder '//dir//'; stopped with it', code(1))
   end subroutine take_folder

   !> Refuse to write over any of names (files in dir) that is there and was not made by
   !> usharp for command: one whose first line begins like none of marks (see begins_like).
   !> force allows it. The error names the first such file and says to add --force (exit 2).
   subroutine check_overwrite(dir, names, marks, command, force, error)
      !> the output folder
      character(len=*), intent(in) :: dir
      !> the files the command is about to write there
      character(len=*), intent(in) :: names(:)
      !> how the first line of each begins when usharp wrote it for the command (none: every
      !> file there is refused)
      character(len=*), intent(in) :: marks(:)
      !> the command's name, for the message
      character(len=*), intent(in) :: command
      !> --force was given
      logical, intent(in) :: force
      type(error_type), allocatable, intent(out) :: error
      character(len=:), allocatable :: file
      integer :: i
      if (force) return
      call check_temporary_names(dir, names, command, error)
      if (allocated(error)) return
      do i = 1, size(names)
         file = join_path(dir, trim(names(i)))
         if (.not. file_exists(file)) cycle
         if (made_by_usharp(file, marks)) cycle
         call fatal_error(error, file//': a file of this name is there that usharp '// &
            command//' did not write; overwrite it with --force, or give another output '// &
            'folder (-o)', stat_usage)
         return
      end do
   end subroutine check_overwrite

   !> Refuse to write any of names (files in dir) where a file of its temporary name is
   !> there: a result file is written under <name>.part, then renamed (usharp_output), so a
   !> file of that name is not usharp's (its own is gone once renamed). The error names the
   !> first and says to add --force (exit 2)
   subroutine check_temporary_names(dir, names, command, error)
      !> the output folder
      character(len=*), intent(in) :: dir
      !> the files the command is about to write there
      character(len=*), intent(in) :: names(:)
      !> the command's name, for the message
      character(len=*), intent(in) :: command
      type(error_type), allocatable, intent(out) :: error
      integer :: i
      do i = 1, size(names)
         if (.not. file_exists(join_path(dir, trim(names(i))//'.part'))) cycle
         call fatal_error(error, join_path(dir, trim(names(i))//'.part')//': a file of this '// &
            'name is there, which usharp '//command//' would write '//trim(names(i))// &
            ' through; move it away, overwrite it with --force, or give another output '// &
            'folder (-o)', stat_usage)
         return
      end do
   end subroutine check_temporary_names

   !> check_overwrite of each of names with its own mark: marks(k) is names(k)'s
   subroutine check_overwrite_each(dir, names, marks, command, force, error)
      !> the output folder
      character(len=*), intent(in) :: dir
      !> the files the command is about to write there, and how the first line of each begins
      !> when usharp wrote it (or '@' and the file beside it that records its hash)
      character(len=*), intent(in) :: names(:), marks(:)
      !> the command's name, for the message
      character(len=*), intent(in) :: command
      !> --force was given
      logical, intent(in) :: force
      type(error_type), allocatable, intent(out) :: error
      integer :: k
      do k = 1, min(size(names), size(marks))
         call check_overwrite(dir, names(k:k), marks(k:k), command, force, error)
         if (allocated(error)) return
      end do
   end subroutine check_overwrite_each

   !> The line that records, in a text file of usharp's beside it, that usharp drew the file
   !> name as it is now (its FNV-1a hash): '# drew fit.png: FNV-1a 0123456789ABCDEF'; '' when
   !> the file cannot be read
   function drawn_line(dir, name) result(line)
      !> the folder of the file
      character(len=*), intent(in) :: dir
      !> the file's name
      character(len=*), intent(in) :: name
      character(len=:), allocatable :: line
      integer(int64) :: hash
      logical :: ok
      line = ''
      call file_hash(join_path(dir, name), hash, ok)
      if (ok) line = '# drew '//name//': FNV-1a '//hash_hex(hash)
   end function drawn_line

   !> Whether the file at path is there and its first line begins like one of marks; a mark
   !> '@<file>' asks instead whether <file> beside it holds the file's drawn_line (a file of
   !> another's of the same name and kind has another hash)
   logical function made_by_usharp(path, marks) result(yes)
      !> the file
      character(len=*), intent(in) :: path
      !> patterns of the first line, as for begins_like
      character(len=*), intent(in) :: marks(:)
      character(len=:), allocatable :: line
      integer :: unit, ios, k
      yes = .false.
      if (.not. file_exists(path)) return
      do k = 1, size(marks)
         if (len_trim(marks(k)) < 2) cycle
         if (marks(k)(1:1) /= '@') cycle
         yes = recorded(path, trim(marks(k)(2:)))
         if (yes) return
      end do
      open (newunit=unit, file=path, status='old', action='read', iostat=ios)
      if (ios /= 0) return
      call read_line(unit, line, ios)
      close (unit)
      if (ios /= 0) return
      do k = 1, size(marks)
         if (marks(k)(1:min(1, len(marks(k)))) == '@') cycle
         if (begins_like(line, trim(marks(k)))) then
            yes = .true.
            return
         end if
      end do
   end function made_by_usharp

   !> Whether the text file record beside the file at path holds path's drawn_line
   logical function recorded(path, record) result(yes)
      character(len=*), intent(in) :: path, record
      character(len=:), allocatable :: dir, name, want, line
      integer :: slash, unit, ios
      yes = .false.
      slash = index(path, '/', back=.true.)
      dir = path(:max(slash - 1, 0))
      name = path(slash + 1:)
      want = drawn_line(dir, name)
      if (len(want) == 0) return
      open (newunit=unit, file=join_path(dir, record), status='old', action='read', iostat=ios)
      if (ios /= 0) return
      do
         call read_line(unit, line, ios)
         if (ios /= 0) exit
         if (line == want) then
            yes = .true.
            exit
         end if
      end do
      close (unit)
   end function recorded

   !> Whether line begins like pattern: its text, where each '*' stands for any text (a
   !> version, a file name); what follows the pattern's end is free
   pure logical function begins_like(line, pattern) result(yes)
      !> the line
      character(len=*), intent(in) :: line
      !> the pattern
      character(len=*), intent(in) :: pattern
      integer :: pos, star, at
      character(len=:), allocatable :: rest
      logical :: first
      yes = .false.
      pos = 1
      rest = pattern
      first = .true.
      do
         star = index(rest, '*')
         if (star == 0) star = len(rest) + 1
         ! The first piece at the line's start, each further one anywhere after the last
         if (star > 1) then
            at = index(line(pos:), rest(:star - 1))
            if (at == 0 .or. (first .and. at /= 1)) return
            pos = pos + at - 1 + star - 1
         end if
         first = .false.
         if (star > len(rest)) exit
         rest = rest(star + 1:)
      end do
      yes = .true.
   end function begins_like

end module usharp_overwrite
