!> Abaqus-style UMAT for the Miller model (also CalculiX, through @ABAQUS_<LIB> materials).
!> Build it with usharp_kinds, usharp_error, usharp_strings, usharp_lapack, usharp_miller,
!> usharp_miller_update and usharp_upf (see the README). Material: *USER MATERIAL,
!> CONSTANTS=13 with E, Poisson, A1, A2, B, C1, C2, k, H1, H2, n, Q, Tm; *DEPVAR 13 (layout in
!> usharp_upf). 3-D elements (NTENS = 6): components 11, 22, 33, 12, 13, 23 with engineering
!> shear strains. A failed local solution sets PNEWDT = 0.25 and leaves the state unchanged.
subroutine umat(stress, statev, ddsdde, sse, spd, scd, rpl, ddsddt, drplde, drpldt, stran, &
                dstran, time, dtime, temp, dtemp, predef, dpred, cmname, ndi, nshr, ntens, &
                nstatv, props, nprops, coords, drot, pnewdt, celent, dfgrd0, dfgrd1, noel, npt, &
                layer, kspt, kstep, kinc)
   use usharp_kinds, only: dp
   use usharp_upf, only: upf_update, perm_abaqus, n_upf_props, n_upf_state
   implicit none
   integer, intent(in) :: ndi, nshr, ntens, nstatv, nprops, noel, npt, layer, kspt, kstep, kinc
   character(len=80), intent(in) :: cmname
   real(dp), intent(inout) :: stress(ntens), statev(nstatv), ddsdde(ntens, ntens)
   real(dp), intent(inout) :: sse, spd, scd, rpl, ddsddt(ntens), drplde(ntens), drpldt
   real(dp), intent(in) :: stran(ntens), dstran(ntens), time(2), dtime, temp, dtemp
   real(dp), intent(in) :: predef(*), dpred(*), props(nprops), coords(3), drot(3, 3)
   real(dp), intent(inout) :: pnewdt
   real(dp), intent(in) :: celent, dfgrd0(3, 3), dfgrd1(3, 3)
   real(dp) :: dwork
   logical :: cut
   if (ntens /= 6 .or. ndi /= 3 .or. nshr /= 3 .or. nprops < n_upf_props .or. &
       nstatv < n_upf_state) then
      pnewdt = 0.25_dp
      return
   end if
   call upf_update(props(1:n_upf_props), temp + dtemp, dtime, perm_abaqus, stran, dstran, stress, &
                   statev(1:n_upf_state), ddsdde, cut, dwork)
   if (cut) then
      pnewdt = 0.25_dp
      return
   end if
   scd = scd + dwork
   rpl = 0.0_dp
   ddsddt = 0.0_dp
   drplde = 0.0_dp
   drpldt = 0.0_dp
end subroutine umat
