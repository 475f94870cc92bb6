!> What the ANSYS USERMAT and Abaqus UMAT adapters share: the property list, the conversion
!> between the FE codes' Voigt vectors (engineering shear strains) and the update's Mandel
!> vectors, the state-variable layout, and the call of the Miller stress update.
!>
!> Properties (the original's TB,USER table, 13 values): 1 E, 2 Poisson, 3 A1, 4 A2, 5 B,
!> 6 C1 (carried for compatibility, not used by the published equations), 7 C2,
!> 8 k (gas constant, cal/(mol K): theta uses Q/k), 9 H1, 10 H2, 11 n, 12 Q (cal/mol),
!> 13 Tm (K). Temperature in K. Stresses in the unit of E and the constants.
!>
!> State variables (13, in the code's component order): 1-6 inelastic strain (engineering
!> shear), 7 drag stress D (0 at the start: D0 is computed from the constants, as the
!> original's TB,STATE initialised it), 8-13 back stress.
module usharp_upf
   use usharp_kinds, only: dp
   use usharp_error, only: error_type
   use usharp_miller, only: miller_model, miller_constants, model_setup, gas_constant
   use usharp_miller_update, only: miller_update, update_status_ok, n_state
   implicit none
   private

   public :: upf_update, upf_props, n_upf_props, n_upf_state, perm_ansys, perm_abaqus

   integer, parameter :: n_upf_props = 13, n_upf_state = 13
   !> Position in the code's 6-vector of each Mandel component (11, 22, 33, 12, 23, 13)
   integer, parameter :: perm_ansys(6) = [1, 2, 3, 4, 5, 6]   ! 11 22 33 12 23 13
   integer, parameter :: perm_abaqus(6) = [1, 2, 3, 4, 6, 5]  ! 11 22 33 12 13 23
   real(dp), parameter :: s2 = sqrt(2.0_dp)
   real(dp), parameter :: w_mandel(6) = [1.0_dp, 1.0_dp, 1.0_dp, s2, s2, s2]

contains

   !> The 13 properties of the TB,USER table (order above) for a model; C1 is written as 0
   pure function upf_props(model) result(props)
      type(miller_model), intent(in) :: model
      real(dp) :: props(n_upf_props)
      props = [model%youngs, model%poisson, model%c%a1, model%c%a2, model%c%b, 0.0_dp, model%c%c2, &
               gas_constant, model%c%h1, model%c%h2, model%c%n, model%c%q, model%tm]
   end function upf_props

   !> One increment for a 3-D stress state (ntens = 6) given in the code's order perm.
   !> stran: strain at the start, dstran: increment (engineering shear), dt: s, temp: K at
   !> the end of the increment. On return stress, statev and ddsdde hold the new values and
   !> cut is .true. when the increment must be repeated smaller (then nothing was changed).
   pure subroutine upf_update(props, temp, dt, perm, stran, dstran, stress, statev, ddsdde, cut, &
                              scd)
      real(dp), intent(in) :: props(n_upf_props), temp, dt
      integer, intent(in) :: perm(6)
      real(dp), intent(in) :: stran(6), dstran(6)
      real(dp), intent(inout) :: stress(6), statev(n_upf_state), ddsdde(6, 6)
      logical, intent(out) :: cut
      real(dp), intent(out) :: scd  !< inelastic work of the increment, sigma : d(eps_in)
      type(miller_model) :: model
      type(error_type), allocatable :: error
      real(dp) :: eps0(6), deps(6), y0(n_state), y(n_state), sig(6), c(6, 6)
      integer :: status, nsub, i, j
      cut = .true.
      scd = 0.0_dp
      model%youngs = props(1)
      model%poisson = props(2)
      model%c = miller_constants(a1=props(3), a2=props(4), b=props(5), c2=props(7), h1=props(9), &
                                 h2=props(10), n=props(11), q=props(12)*gas_constant/props(8))
      model%tm = props(13)
      model%temperature = temp
      call model_setup(model, error)
      if (allocated(error)) return
      ! Code order, engineering shear -> Mandel
      do i = 1, 6
         eps0(i) = stran(perm(i))*merge(1.0_dp, 1.0_dp/s2, i <= 3)
         deps(i) = dstran(perm(i))*merge(1.0_dp, 1.0_dp/s2, i <= 3)
         y0(i) = statev(perm(i))*merge(1.0_dp, 1.0_dp/s2, i <= 3)
         y0(6 + i) = statev(7 + perm(i))*w_mandel(i)
      end do
      y0(13) = statev(7)
      if (y0(13) <= 0.0_dp) y0(13) = model%d0
      call miller_update(model, eps0, deps, dt, y0, sig, y, c, status, nsub)
      if (status /= update_status_ok) return
      cut = .false.
      scd = dot_product(sig, y(1:6) - y0(1:6))
      do i = 1, 6
         stress(perm(i)) = sig(i)/w_mandel(i)
         statev(perm(i)) = y(i)*merge(1.0_dp, s2, i <= 3)
         statev(7 + perm(i)) = y(6 + i)/w_mandel(i)
         do j = 1, 6
            ddsdde(perm(i), perm(j)) = c(i, j)/w_mandel(i)*merge(1.0_dp, 1.0_dp/s2, j <= 3)
         end do
      end do
      statev(7) = y(13)
   end subroutine upf_update
end module usharp_upf
