!> Weighting functions of the objective (thesis Section 4 and Appendix B)
module usharp_weighting
   use usharp_kinds, only: dp
   use usharp_forcing, only: noise_sd, smooth_branch
   implicit none
   private

   public :: threshold_weights, relaxation_weights, rate_signal

   !> Largest weight of both weighting functions
   real(dp), parameter, public :: w_max = 2.5_dp

   !> Data whose noise (robust, from second differences) is below this share of their peak
   !> are their own rate signal (rate_signal): a simulation's values written to a file
   real(dp), parameter :: noise_free = 1.0e-4_dp

contains

   !> LCFFUNC: w = 2.5 where |stress| > sig (inelastic deformation), else 1
   pure function threshold_weights(stress, sig) result(w)
      real(dp), intent(in) :: stress(:)  !< experimental stress at the simulation times
      real(dp), intent(in) :: sig        !< threshold, model unit
      real(dp) :: w(size(stress))
      w = merge(w_max, 1.0_dp, abs(stress) > sig)
   end function threshold_weights

   !> Relaxation weights (Eqs. 9-11): w = (C0 + C1|s'| + C2|s''|)/(C0 - C1|s'| - C2|s''|),
   !> C1 = 1 s/unit, C2 = 1 s**2/unit, C0 = 7/3 (C1|s'_max| + C2|s''(t_max)|), so w = 2.5
   !> where relaxation is fastest and w -> 1 as it dies out. s' is a forward difference,
   !> s'' a three-point second difference on the (possibly uneven) times; the first and last
   !> points get weight 0; weights are limited to 2.5 (also where the denominator is <= 0).
   !> in_hold marks the points of hold segments: the maximum rate is taken there (the rate
   !> of relaxation, not of loading); with no hold point, over all points.
   pure function relaxation_weights(t, stress, in_hold) result(w)
      real(dp), intent(in) :: t(:), stress(:)
      logical, intent(in) :: in_hold(:)
      real(dp) :: w(size(t))
      real(dp), parameter :: c1 = 1.0_dp, c2 = 1.0_dp
      real(dp) :: sd(size(t)), sdd(size(t)), c0, num, den
      logical :: pick(size(t))
      integer :: i, n, imax
      n = size(t)
      w = 0.0_dp
      if (n < 3) return
      sd = 0.0_dp
      sdd = 0.0_dp
      do i = 2, n - 1
         sd(i) = (stress(i + 1) - stress(i))/(t(i + 1) - t(i))
         sdd(i) = 2.0_dp*((stress(i + 1) - stress(i))/(t(i + 1) - t(i)) - &
                          (stress(i) - stress(i - 1))/(t(i) - t(i - 1)))/(t(i + 1) - t(i - 1))
      end do
      pick = in_hold
      pick(1) = .false.
      pick(n) = .false.
      if (.not. any(pick)) pick(2:n - 1) = .true.
      imax = maxloc(abs(sd), dim=1, mask=pick)
      c0 = 7.0_dp/3.0_dp*(c1*abs(sd(imax)) + c2*abs(sdd(imax)))
      if (c0 <= 0.0_dp) then
         ! No relaxation at all: nothing to emphasise
         w(2:n - 1) = 1.0_dp
         return
      end if
      do i = 2, n - 1
         num = c0 + c1*abs(sd(i)) + c2*abs(sdd(i))
         den = c0 - c1*abs(sd(i)) - c2*abs(sdd(i))
         if (den <= 0.0_dp) then
            w(i) = w_max
         else
            w(i) = min(num/den, w_max)
         end if
      end do
   end function relaxation_weights

   !> The stress whose rates the relaxation weighting takes (relaxation_weights): the data
   !> themselves where they are free of noise to noise_free of their peak; else each piece
   !> of the control history (a ramp, a hold; corners tc) smoothed to the data's noise
   !> (smooth_branch). Differenced as they are, noisy data give rates of the noise: a sample
   !> that its noise moved got a larger weight, so the weighted objective of a fit to data
   !> without any unmodelled effect stood 19 % above its noise part on average (1.04 to
   !> 1.45 over 44 tests with 0.5 % noise), which a diagnosis read as a structured gap
   pure function rate_signal(t, y, tc) result(z)
      real(dp), intent(in) :: t(:)   !< times of the data, s, increasing
      real(dp), intent(in) :: y(:)   !< the measured stress at t
      real(dp), intent(in) :: tc(:)  !< the corners of the control history, s, increasing
      real(dp) :: z(size(y))
      real(dp) :: sigma
      integer :: piece(size(t)), i, i0, k, n
      z = y
      n = size(y)
      if (n < 5) return
      sigma = noise_sd(y)
      if (.not. sigma > noise_free*maxval(abs(y))) return
      ! Each sample's piece: the first corner at or after it (a sample at a corner ends the
      ! piece before it)
      k = 1
      do i = 1, n
         do while (k < size(tc))
            if (tc(k) >= t(i)) exit
            k = k + 1
         end do
         piece(i) = k
      end do
      i0 = 1
      do i = 1, n
         if (i < n) then
            if (piece(i + 1) == piece(i)) cycle
         end if
         z(i0:i) = smooth_branch(t(i0:i), y(i0:i), sigma)
         i0 = i + 1
      end do
   end function rate_signal
end module usharp_weighting
