!> Abaqus-style UMAT for the Miller model (also CalculiX, through @ABAQUS_<LIB> materials).
!> Material: *USER MATERIAL, CONSTANTS=13 with E, Poisson, A1, A2, B, C1, C2, k, H1, H2, n,
!> Q, Tm; *DEPVAR 13 (layout in usharp_upf). Elements: 3-D (NTENS = 6: 11, 22, 33, 12, 13,
!> 23), plane strain and axisymmetric (NTENS = 4: 11, 22, 33, 12), plane stress and shells
!> (NTENS = 3: 11, 22, 12); engineering shear strains. SSE: elastic strain energy density,
!> SPD: inelastic work (the viscoplastic dissipation, rate-dependent and rate-independent
!> alike), SCD unchanged. A failed local solution sets PNEWDT = 0.25 and leaves stress and
!> state unchanged, DDSDDE elastic; an unusable material is reported (usharp_upf_report)
!> and PNEWDT set to 1e-6, so that the analysis stops.
subroutine umat(stress, statev, ddsdde, sse, spd, scd, rpl, ddsddt, drplde, drpldt, stran, &
                dstran, time, dtime, temp, dtemp, predef, dpred, cmname, ndi, nshr, ntens, &
                nstatv, props, nprops, coords, drot, pnewdt, celent, dfgrd0, dfgrd1, noel, npt, &
                layer, kspt, kstep, kinc)
   use usharp_kinds, only: dp
   use usharp_upf, only: upf_update, upf_result, upf_elastic_tangent, perm_abaqus, &
                         upf_ok, upf_cut, upf_call_problem
   use usharp_model_miller, only: miller_model
   use usharp_upf_report, only: upf_report_invalid, upf_report_stops
   implicit none
   integer, intent(in) :: ndi, nshr, ntens, nstatv, nprops, noel, npt, layer, kspt, kstep, kinc
   character(len=80), intent(in) :: cmname
   real(dp), intent(inout) :: stress(ntens), statev(nstatv), ddsdde(ntens, ntens)
   real(dp), intent(inout) :: sse, spd, scd, rpl, ddsddt(ntens), drplde(ntens), drpldt
   real(dp), intent(in) :: stran(ntens), dstran(ntens), time(2), dtime, temp, dtemp
   real(dp), intent(in) :: predef(*), dpred(*), props(nprops), coords(3), drot(3, 3)
   real(dp), intent(inout) :: pnewdt
   real(dp), intent(in) :: celent, dfgrd0(3, 3), dfgrd1(3, 3)
   !> Increment factors asked for after a failed local solution and for an unusable material
   !> (small enough that the code stops at its minimum increment)
   real(dp), parameter :: cut_factor = 0.25_dp, stop_factor = 1.0e-6_dp
   type(upf_result) :: res
   !> The model this adapter serves, set up from the properties at every call
   type(miller_model) :: model
   character(len=40) :: card
   rpl = 0.0_dp
   ddsddt = 0.0_dp
   drplde = 0.0_dp
   drpldt = 0.0_dp
   write (card, '(a,i0)') '*USER MATERIAL, CONSTANTS=', model%n_props()
   res%message = upf_call_problem(model, nprops, nstatv, ndi, nshr, trim(card), '*DEPVAR', 'NDI', &
                                  'NSHR')
   if (len_trim(res%message) == 0) then
      call upf_update(model, props(1:nprops), temp + dtemp, dtime, perm_abaqus, ntens, stran, &
                      dstran, stress, statev(1:model%n_state()), ddsdde, res)
      if (res%status == upf_ok) then
         sse = res%sse
         spd = spd + res%dspd
         return
      else if (res%status == upf_cut) then
         call ask_smaller(pnewdt, cut_factor)
         return
      end if
   end if
   call upf_elastic_tangent(props, perm_abaqus, ntens, ddsdde)
   ! One line per element (its first integration point), not per point; where the report
   ! ends the analysis (Abaqus), at whichever point first finds the problem (a temperature at
   ! or above Tm may be one point's)
   if (npt == 1 .or. upf_report_stops) call upf_report_invalid(cmname, res%message)
   call ask_smaller(pnewdt, stop_factor)
contains
   !> Ask for the increment scaled by factor unless a smaller one is asked already. Abaqus
   !> passes PNEWDT large, CalculiX -1 (no request): both read a value in (0, 1) as a cut.
   pure subroutine ask_smaller(pnewdt, factor)
      real(dp), intent(inout) :: pnewdt
      real(dp), intent(in) :: factor
      if (.not. (pnewdt > 0.0_dp .and. pnewdt <= factor)) pnewdt = factor
   end subroutine ask_smaller
end subroutine umat
