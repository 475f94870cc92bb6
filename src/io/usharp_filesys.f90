!> File-system helpers through the C library (no shell involved)
module usharp_filesys
   use, intrinsic :: iso_c_binding, only: c_int, c_char, c_null_char
   use usharp_error, only: error_type, fatal_error, stat_io
   implicit none
   private

   public :: make_dir, join_path, file_exists

   interface
      function c_mkdir(path, mode) bind(C, name='mkdir') result(stat)
         import :: c_int, c_char
         character(kind=c_char), intent(in) :: path(*)
         integer(c_int), value, intent(in) :: mode
         integer(c_int) :: stat
      end function c_mkdir
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

   !> Whether a file exists
   logical function file_exists(path)
      character(len=*), intent(in) :: path
      inquire (file=path, exist=file_exists)
   end function file_exists
end module usharp_filesys
