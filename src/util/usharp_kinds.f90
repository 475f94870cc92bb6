!> Kind parameters used throughout usharp.
module usharp_kinds
   use, intrinsic :: iso_fortran_env, only: real64, int64
   implicit none
   private

   !> Double precision real kind
   integer, parameter, public :: dp = real64
   !> 64-bit integer kind (counters, seeds)
   integer, parameter, public :: i8 = int64
end module usharp_kinds
