!> Units: stress units, and the gas constant of the activation energies (cal/mol)
module usharp_units
   use usharp_kinds, only: dp
   implicit none
   private

   public :: stress_factor

   !> MPa in one ksi
   real(dp), parameter, public :: ksi_to_mpa = 6.894757293168361_dp
   !> Gas constant in cal/(mol K): activation energies are in cal/mol, as the thesis's Q
   real(dp), parameter, public :: gas_constant = 1.9859_dp

contains

   !> Factor that converts a stress from unit 'from' to unit 'to' (ksi or MPa)
   pure real(dp) function stress_factor(from, to) result(f)
      character(len=*), intent(in) :: from, to
      f = 1.0_dp
      if (from == to) return
      if (from == 'ksi' .and. to == 'MPa') f = ksi_to_mpa
      if (from == 'MPa' .and. to == 'ksi') f = 1.0_dp/ksi_to_mpa
   end function stress_factor
end module usharp_units
