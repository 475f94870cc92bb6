!> File-system helpers through the C library (no shell involved)
module usharp_filesys
   use, intrinsic :: iso_c_binding, only: c_int, c_char, c_null_char, c_ptr, c_null_ptr, &
                                          c_associated
   use usharp_error, only: error_type, fatal_error, stat_io
   use usharp_strings, only: shell_quote
   implicit none
   private

   public :: make_dir, join_path, file_exists, absolute_path, remove_file, remove_dir

   interface
      function c_mkdir(path, mode) bind(C, name='mkdir') result(stat)
         import :: c_int, c_char
         character(kind=c_char), intent(in) :: path(*)
         integer(c_int), value, intent(in) :: mode
         integer(c_int) :: stat
      end function c_mkdir
      function c_realpath(path, resolved) bind(C, name='realpath') result(res)
         import :: c_char, c_ptr
         character(kind=c_char), intent(in) :: path(*)
         character(kind=c_char), intent(out) :: resolved(*)
         type(c_ptr) :: res
      end function c_realpath
      function c_remove(path) bind(C, name='remove') result(stat)
         import :: c_int, c_char
         character(kind=c_char), intent(in) :: path(*)
         integer(c_int) :: stat
      end function c_remove
   end interface

contains

   !> Create a folder and its parents (like mkdir -p); an error if it cannot be made or written
   subroutine make_dir(path, error)
      character(len=*), intent(in) :: path
      type(error_type), allocatable, intent(out) :: error
      integer :: k, stat, unit, ios
      character(len=256) :: msg
      do k = 2, len_trim(path) + 1
         if (k <= len_trim(path)) then
            if (path(k:k) /= '/') cycle
         end if
         stat = c_mkdir(path(:k - 1)//c_null_char, int(o'755', c_int))
      end do
      ! Prove the folder is writable by creating and deleting a file in it
      open (newunit=unit, file=join_path(path, '.usharp-write-test'), status='replace', &
            action='write', iostat=ios, iomsg=msg)
      if (ios /= 0) then
         call fatal_error(error, path//': output folder cannot be created or written ('// &
            trim(msg)//')', stat_io)
         return
      end if
      close (unit, status='delete')
   end subroutine make_dir

   !> dir/name
   pure function join_path(dir, name) result(path)
      character(len=*), intent(in) :: dir, name
      character(len=:), allocatable :: path
      if (len(dir) == 0) then
         path = name
      else if (dir(len(dir):len(dir)) == '/') then
         path = dir//name
      else
         path = dir//'/'//name
      end if
   end function join_path

   !> The absolute path of an existing file or folder ('' if it does not exist)
   function absolute_path(path) result(abs_path)
      character(len=*), intent(in) :: path
      character(len=:), allocatable :: abs_path
      character(kind=c_char) :: buf(4097)
      integer :: k
      abs_path = ''
      buf = c_null_char
      if (.not. c_associated(c_realpath(trim(path)//c_null_char, buf))) return
      do k = 1, size(buf)
         if (buf(k) == c_null_char) exit
         abs_path = abs_path//buf(k)
      end do
   end function absolute_path

   !> Remove a file or an empty folder; .true. when it is gone
   logical function remove_file(path) result(ok)
      character(len=*), intent(in) :: path
      logical :: exists
      ok = c_remove(path//c_null_char) == 0
      if (.not. ok) then
         inquire (file=path, exist=exists)
         ok = .not. exists
      end if
   end function remove_file

   !> Remove a folder with the files named in it; whatever else is there is removed by rm -r
   subroutine remove_dir(path, names)
      character(len=*), intent(in) :: path
      character(len=*), intent(in) :: names(:)
      integer :: k, stat
      logical :: gone
      do k = 1, size(names)
         gone = remove_file(join_path(path, trim(names(k))))
      end do
      if (c_remove(path//c_null_char) == 0) return
      call execute_command_line('rm -rf '//shell_quote(path), exitstat=stat)
   end subroutine remove_dir

   !> Whether a file exists
   logical function file_exists(path)
      character(len=*), intent(in) :: path
      inquire (file=path, exist=file_exists)
   end function file_exists
end module usharp_filesys
