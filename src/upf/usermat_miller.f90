!> ANSYS USERMAT for the Miller model. Material: TB,USER,mat,1,13 with E, Poisson, A1, A2, B,
!> C1, C2, k, H1, H2, n, Q, Tm; TB,STATE,mat,,13 (layout in usharp_upf). Elements: 3-D
!> solids (ncomp = 6: 11, 22, 33, 12, 23, 13), plane strain and axisymmetric (ncomp = 4: 11,
!> 22, 33, 12), plane stress (ncomp = 3, nDirect = 2: 11, 22, 12; epsZZ returns the thickness
!> strain); engineering shear strains. sedEl: elastic strain energy density, sedPl:
!> inelastic work, epseq: accumulated equivalent inelastic strain, epsPl: inelastic strain.
!> A failed local solution sets keycut = 1 and cutFactor = 0.25 (ANSYS bisects), leaving
!> stress and state unchanged and dsdePl elastic; an unusable material is reported
!> (usharp_upf_report) and keycut set to 1.
subroutine usermat(matId, elemId, kDomIntPt, kLayer, kSectPt, ldstep, isubst, keycut, &
                   nDirect, nShear, ncomp, nStatev, nProp, Time, dTime, Temp, dTemp, &
                   stress, ustatev, dsdePl, sedEl, sedPl, epseq, Strain, dStrain, epsPl, &
                   prop, coords, var0, defGrad_t, defGrad, tsstif, epsZZ, cutFactor, &
                   var1, var2, var3, var4, var5, var6, var7)
   use usharp_kinds, only: dp
   use usharp_upf, only: upf_update, upf_result, upf_elastic_tangent, perm_ansys, &
                         upf_ok, upf_cut, upf_call_problem
   use usharp_model_miller, only: miller_model
   use usharp_upf_report, only: upf_report_invalid, upf_report_stops
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
   type(upf_result) :: res
   !> The model this adapter serves, set up from the properties at every call
   type(miller_model) :: model
   character(len=40) :: cards(2)
   character(len=12) :: mat
   integer :: i
   keycut = 0
   write (cards(1), '(a,i0)') 'TB,USER,mat,1,', model%n_props()
   write (cards(2), '(a,i0)') 'TB,STATE,mat,,', model%n_state()
   res%message = upf_call_problem(model, nProp, nStatev, nDirect, nShear, trim(cards(1)), &
                                  trim(cards(2)), 'nDirect', 'nShear')
   if (len_trim(res%message) == 0) then
      call upf_update(model, prop(1:nProp), Temp + dTemp, dTime, perm_ansys, ncomp, Strain, &
                      dStrain, stress, ustatev(1:model%n_state()), dsdePl, res)
      if (res%status == upf_ok) then
         sedEl = res%sse
         sedPl = sedPl + res%dspd
         epseq = epseq + res%deqin
         ! Inelastic strain in the element's components (the state holds all six)
         if (ncomp == 3) then
            epsPl = ustatev([1, 2, 4])
            epsZZ = res%eps33
            ! Transverse shear stiffness of shells: elastic, G
            tsstif = prop(1)/(2.0_dp*(1.0_dp + prop(2)))
         else
            epsPl = [(ustatev(i), i = 1, ncomp)]
         end if
         return
      else if (res%status == upf_cut) then
         keycut = 1
         cutFactor = 0.25_dp
         return
      end if
   end if
   call upf_elastic_tangent(prop, perm_ansys, ncomp, dsdePl)
   keycut = 1
   cutFactor = 0.25_dp
   write (mat, '(i0)') matId
   ! As in umat_miller: once per element unless the report ends the analysis
   if (kDomIntPt == 1 .or. upf_report_stops) call upf_report_invalid(mat, res%message)
end subroutine usermat
