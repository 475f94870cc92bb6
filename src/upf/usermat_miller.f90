!> ANSYS USERMAT for the Miller model (3-D solids such as SOLID185). Build it into the ANSYS
!> user-programmable-feature library with usharp_kinds, usharp_error, usharp_strings,
!> usharp_lapack, usharp_miller, usharp_miller_update and usharp_upf. Material:
!> TB,USER,mat,1,13 with E, Poisson, A1, A2, B, C1, C2, k, H1, H2, n, Q, Tm;
!> TB,STATE,mat,,13 (see usharp_upf for the layout). Components 11, 22, 33, 12, 23, 13 with
!> engineering shear strains. A failed local solution sets keycut = 1 so that ANSYS bisects.
subroutine usermat(matId, elemId, kDomIntPt, kLayer, kSectPt, ldstep, isubst, keycut, &
                   nDirect, nShear, ncomp, nStatev, nProp, Time, dTime, Temp, dTemp, &
                   stress, ustatev, dsdePl, sedEl, sedPl, epseq, Strain, dStrain, epsPl, &
                   prop, coords, var0, defGrad_t, defGrad, tsstif, epsZZ, cutFactor, &
                   var1, var2, var3, var4, var5, var6, var7)
   use usharp_kinds, only: dp
   use usharp_upf, only: upf_update, perm_ansys, n_upf_props, n_upf_state
   implicit none
   integer, intent(in) :: matId, elemId, kDomIntPt, kLayer, kSectPt, ldstep, isubst
   integer, intent(out) :: keycut
   integer, intent(in) :: nDirect, nShear, ncomp, nStatev, nProp
   real(dp), intent(in) :: Time, dTime, Temp, dTemp
   real(dp), intent(inout) :: stress(ncomp), ustatev(nStatev)
   real(dp), intent(out) :: dsdePl(ncomp, ncomp)
   real(dp), intent(inout) :: sedEl, sedPl, epseq
   real(dp), intent(in) :: Strain(ncomp), dStrain(ncomp)
   real(dp), intent(inout) :: epsPl(ncomp)
   real(dp), intent(in) :: prop(nProp), coords(3), var0
   real(dp), intent(in) :: defGrad_t(3, 3), defGrad(3, 3)
   real(dp), intent(inout) :: tsstif(2), epsZZ
   real(dp), intent(inout) :: cutFactor
   real(dp), intent(inout) :: var1, var2, var3, var4, var5, var6, var7
   real(dp) :: dwork, ddsdde(6, 6)
   logical :: cut
   keycut = 0
   if (ncomp /= 6 .or. nProp < n_upf_props .or. nStatev < n_upf_state) then
      keycut = 1
      return
   end if
   ddsdde = 0.0_dp
   call upf_update(prop(1:n_upf_props), Temp + dTemp, dTime, perm_ansys, Strain, dStrain, stress, &
                   ustatev(1:n_upf_state), ddsdde, cut, dwork)
   if (cut) then
      keycut = 1
      cutFactor = 0.25_dp
      return
   end if
   dsdePl = ddsdde
   epsPl(1:6) = ustatev(1:6)
   sedPl = sedPl + dwork
end subroutine usermat
