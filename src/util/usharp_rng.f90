!> A small deterministic random number generator (xorshift64 with Box-Muller normals), so that
!> synthetic noisy data are reproducible bit for bit on every compiler and platform.
module usharp_rng
   use usharp_kinds, only: dp, i8
   use usharp_math, only: log_dp, sincos_turn
   implicit none
   private

   public :: rng_type

   !> Generator state
   type :: rng_type
      integer(i8) :: state = 0_i8
   contains
      procedure :: seed => rng_seed
      procedure :: skip => rng_skip
      procedure :: uniform => rng_uniform
      procedure :: normal => rng_normal
   end type rng_type

contains

   !> Start the sequence from an integer seed
   pure subroutine rng_seed(self, seed)
      class(rng_type), intent(inout) :: self
      integer, intent(in) :: seed
      ! A zero state would stay zero; mix the seed into a fixed odd pattern
      self%state = ieor(int(z'2545F4914F6CDD1D', i8), int(seed, i8))
      if (self%state == 0_i8) self%state = 1_i8
   end subroutine rng_seed

   !> Pass over n outputs. Seeds that differ in a few low bits start from states that differ
   !> in those bits only, so their first draws are nearly equal; after some 64 steps of the
   !> shift-xor recurrence the difference has spread over all 64 bits.
   impure subroutine rng_skip(self, n)
      class(rng_type), intent(inout) :: self
      integer, intent(in) :: n
      integer(i8) :: z
      integer :: i
      do i = 1, n
         z = next_bits(self)
      end do
   end subroutine rng_skip

   !> Next 64-bit output of Marsaglia's xorshift64 (13, 7, 17): shifts and exclusive ors only,
   !> so no integer overflow and the same bits on every platform
   impure integer(i8) function next_bits(self) result(z)
      class(rng_type), intent(inout) :: self
      z = self%state
      z = ieor(z, shiftl(z, 13))
      z = ieor(z, shiftr(z, 7))
      z = ieor(z, shiftl(z, 17))
      self%state = z
   end function next_bits

   !> Uniform number in (0, 1) with 53 random bits
   impure real(dp) function rng_uniform(self) result(u)
      class(rng_type), intent(inout) :: self
      integer(i8) :: bits
      bits = shiftr(next_bits(self), 11)
      u = (real(bits, dp) + 0.5_dp)*2.0_dp**(-53)
   end function rng_uniform

   !> Standard normal number (Box-Muller, one of the pair)
   impure real(dp) function rng_normal(self) result(x)
      class(rng_type), intent(inout) :: self
      real(dp) :: u1, u2, s, c
      u1 = self%uniform()
      u2 = self%uniform()
      call sincos_turn(u2, s, c)
      x = sqrt(-2.0_dp*log_dp(u1))*c
   end function rng_normal

end module usharp_rng
