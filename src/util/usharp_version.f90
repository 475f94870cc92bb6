!> Version of the program
module usharp_version
   implicit none
   private

   !> Version string, kept equal to fpm.toml
   character(len=*), parameter, public :: usharp_version_string = '0.1.0'
end module usharp_version
