!> Version of the program, and the identity of the build that runs
module usharp_version
   use, intrinsic :: iso_fortran_env, only: int64
   use usharp_filesys, only: file_hash, hash_hex
   implicit none
   private

   public :: build_id

   !> Version string, kept equal to fpm.toml
   character(len=*), parameter, public :: usharp_version_string = '0.1.0'

contains

   !> The build of the running program: a hash of its executable file (16 hexadecimal
   !> digits), 'unknown' where the system does not show it (/proc/self/exe). A journal keeps
   !> it, so that a run is resumed only by the build that began it: another build may order or
   !> compute its steps otherwise, and a resumed run is to equal an uninterrupted one bit for bit
   function build_id() result(id)
      character(len=:), allocatable :: id
      integer(int64) :: hash
      logical :: ok
      call file_hash('/proc/self/exe', hash, ok)
      if (ok) then
         id = hash_hex(hash)
      else
         id = 'unknown'
      end if
   end function build_id
end module usharp_version
