!> What the ANSYS USERMAT and Abaqus UMAT adapters share, for any model (usharp_model): the
!> property list and its checks, the conversion between the FE codes' Voigt vectors
!> (engineering shear strains) and the update's Mandel vectors for 3-D, plane strain,
!> axisymmetric and plane stress elements, the state-variable layout, the energies, and the
!> call of the model's stress update. An adapter passes a model of its kind, which the
!> property list sets up at the increment's temperature.
!>
!> Properties: the model's list (to_props), whose first two are E and Poisson's ratio. The
!> Miller model's (the original's TB,USER table, 13 values): 1 E, 2 Poisson, 3 A1, 4 A2, 5 B,
!> 6 C1 (carried for compatibility, not used by the published equations), 7 C2,
!> 8 k (gas constant, cal/(mol K): theta uses Q/k), 9 H1, 10 H2, 11 n, 12 Q (cal/mol),
!> 13 Tm (K). Temperature in K. Stresses in the unit of E and the constants.
!>
!> State variables: the model's blocks (fe_layout) in the code's 3-D component order whatever
!> the element, tensors of strain with engineering shear. The Miller model's (13): 1-6
!> inelastic strain, 7 drag stress D (0 at the start: D0 is computed from the constants, as
!> the original's TB,STATE initialised it), 8-13 back stress.
!>
!> Element families (ntens components of stress and strain in the code's vectors):
!> 6: 3-D (code order perm), 4: plane strain and axisymmetric (11, 22, 33, 12),
!> 3: plane stress and shells (11, 22, 12; the out-of-plane strain is solved for s33 = 0).
module usharp_upf
   use usharp_kinds, only: dp
   use usharp_error, only: error_type
   use usharp_model, only: model_type, update_status_ok, update_status_cut, elastic_moduli, &
                           block_strain, block_stress
   implicit none
   private

   public :: upf_update, upf_update_material
   public :: upf_elastic_tangent, upf_call_problem
   public :: upf_result, perm_ansys, perm_abaqus
   public :: upf_ok, upf_cut, upf_invalid

   !> Position in the code's 6-vector of each Mandel component (11, 22, 33, 12, 23, 13)
   integer, parameter :: perm_ansys(6) = [1, 2, 3, 4, 5, 6]   ! 11 22 33 12 23 13
   integer, parameter :: perm_abaqus(6) = [1, 2, 3, 4, 6, 5]  ! 11 22 33 12 13 23
   !> Outcome of an increment: done, repeat it smaller, or the material cannot be used
   integer, parameter :: upf_ok = 0, upf_cut = 1, upf_invalid = 2
   real(dp), parameter :: s2 = sqrt(2.0_dp)
   real(dp), parameter :: w_mandel(6) = [1.0_dp, 1.0_dp, 1.0_dp, s2, s2, s2]
   !> Out-of-plane stress accepted by the plane-stress solution, relative to the largest of
   !> the stress and 1e-3 E; Newton iterations allowed for it
   real(dp), parameter :: tol_plane_stress = 1.0e-12_dp
   integer, parameter :: max_plane_stress_iterations = 30

   !> What an increment returns besides stress, state and tangent
   type :: upf_result
      integer :: status = upf_cut        !< upf_ok, upf_cut or upf_invalid
      real(dp) :: sse = 0.0_dp           !< elastic strain energy density at the end, sigma:eps_el/2
      real(dp) :: dspd = 0.0_dp          !< inelastic work of the increment (trapezoid rule)
      real(dp) :: deqin = 0.0_dp         !< equivalent inelastic strain increment
      real(dp) :: eps33 = 0.0_dp         !< plane stress: out-of-plane strain at the end
      character(len=200) :: message = '' !< why the material is invalid (upf_invalid)
   end type upf_result

contains

   !> What is wrong with a call before any property is read: too few properties or state
   !> variables, or an element family the update does not serve (ndi direct and nshr shear
   !> components). Empty when the call can go ahead. The cards and names are the code's own,
   !> so that the message says what to change in its input.
   pure function upf_call_problem(model, nprops, nstatv, ndi, nshr, props_card, state_card, &
                                  ndi_name, nshr_name) result(message)
      class(model_type), intent(in) :: model
      integer, intent(in) :: nprops, nstatv, ndi, nshr
      character(len=*), intent(in) :: props_card, state_card, ndi_name, nshr_name
      character(len=200) :: message
      message = ''
      if (nprops < model%n_props()) then
         write (message, '(a,i0,a,i0)') 'needs ', model%n_props(), ' constants ('//props_card// &
            '), got ', nprops
      else if (nstatv < model%n_state()) then
         write (message, '(a,i0,a,i0)') 'needs ', model%n_state(), ' state variables ('// &
            state_card//'), got ', nstatv
      else if (.not. ((ndi == 3 .and. (nshr == 3 .or. nshr == 1)) .or. &
                      (ndi == 2 .and. nshr == 1))) then
         write (message, '(a,i0,a,i0,a)') 'elements with '//ndi_name//' = ', ndi, ', '// &
            nshr_name//' = ', nshr, ' are not supported (3-D, plane strain, axisymmetric, '// &
            'plane stress only)'
      end if
   end function upf_call_problem

   !> Isotropic elastic tangent in the code's order for ntens components (plane stress
   !> condensed; for other ntens a diagonal of E) from the first two properties, E and
   !> Poisson, replaced by 1 and 0 when absent or unusable: a cut-back or a rejected material
   !> always returns a finite, positive definite matrix
   pure subroutine upf_elastic_tangent(props, perm, ntens, ddsdde)
      real(dp), intent(in) :: props(:)
      integer, intent(in) :: perm(6), ntens
      real(dp), intent(out) :: ddsdde(ntens, ntens)
      real(dp) :: c(6, 6), g, k, youngs, poisson
      integer :: i, j
      youngs = 1.0_dp
      poisson = 0.0_dp
      if (size(props) >= 2) then
         if (props(1) > 0.0_dp .and. props(1) < huge(1.0_dp)) youngs = props(1)
         if (props(2) > -1.0_dp .and. props(2) < 0.5_dp) poisson = props(2)
      end if
      if (ntens /= 6 .and. ntens /= 4 .and. ntens /= 3) then
         ddsdde = 0.0_dp
         do i = 1, ntens
            ddsdde(i, i) = youngs
         end do
         return
      end if
      call elastic_moduli(youngs, poisson, g, k)
      c = 0.0_dp
      do i = 1, 3
         do j = 1, 3
            c(i, j) = k - 2.0_dp*g/3.0_dp
         end do
         c(i, i) = k + 4.0_dp*g/3.0_dp
         c(3 + i, 3 + i) = 2.0_dp*g
      end do
      call tangent_to_code(c, positions(perm, ntens), ntens, ddsdde)
   end subroutine upf_elastic_tangent

   !> Code position of each Mandel component (0 when the element has none): 3-D in the
   !> code's order, ntens 4 as 11 22 33 12, ntens 3 as 11 22 12
   pure function positions(perm, ntens) result(pos)
      integer, intent(in) :: perm(6), ntens
      integer :: pos(6)
      select case (ntens)
      case (6); pos = perm
      case (4); pos = [1, 2, 3, 4, 0, 0]
      case default; pos = [1, 2, 0, 3, 0, 0]
      end select
   end function positions

   !> The Mandel tangent (for ntens = 3 condensed so that s33 = 0) in the code's order
   pure subroutine tangent_to_code(c, pos, ntens, ddsdde)
      real(dp), intent(in) :: c(6, 6)
      integer, intent(in) :: pos(6), ntens
      real(dp), intent(out) :: ddsdde(ntens, ntens)
      real(dp) :: cc(6, 6)
      integer :: i, j
      cc = c
      if (ntens == 3) then
         do j = 1, 6
            cc(:, j) = c(:, j) - c(:, 3)*c(3, j)/c(3, 3)
         end do
      end if
      ddsdde = 0.0_dp
      do j = 1, 6
         if (pos(j) == 0) cycle
         do i = 1, 6
            if (pos(i) == 0) cycle
            ddsdde(pos(i), pos(j)) = cc(i, j)/w_mandel(i)*merge(1.0_dp, 1.0_dp/s2, j <= 3)
         end do
      end do
   end subroutine tangent_to_code

   !> One increment of a material point. model: a model of the material's kind, set up here
   !> from props, its property list; temp: K at the end of the
   !> increment; dt: s; perm: the code's 3-D order (perm_ansys or perm_abaqus); ntens: 6, 4
   !> or 3 (see the module header). stran: strain at the start, dstran: its increment
   !> (engineering shear), in the code's order for ntens components. On return with
   !> res%status = upf_ok, stress, statev and ddsdde hold the end values; otherwise stress
   !> and statev are unchanged and ddsdde is the elastic tangent (upf_cut: repeat the
   !> increment smaller; upf_invalid: res%message says which property is unusable).
   pure subroutine upf_update(model, props, temp, dt, perm, ntens, stran, dstran, stress, statev, &
                              ddsdde, res)
      class(model_type), intent(inout) :: model
      real(dp), intent(in) :: props(:), temp, dt
      integer, intent(in) :: perm(6), ntens
      real(dp), intent(in) :: stran(ntens), dstran(ntens)
      real(dp), intent(inout) :: stress(ntens), statev(:)
      real(dp), intent(out) :: ddsdde(ntens, ntens)
      type(upf_result), intent(out) :: res
      call upf_elastic_tangent(props, perm, ntens, ddsdde)
      res%status = upf_invalid
      call model%from_props(props, temp, res%message)
      if (len_trim(res%message) > 0) return
      call upf_update_material(model, dt, perm, ntens, stran, dstran, stress, statev, ddsdde, res)
   end subroutine upf_update

   !> The same increment for a model already set up (from_props): the entry point that holds
   !> no property list. On upf_cut and upf_invalid ddsdde is elastic.
   pure subroutine upf_update_material(model, dt, perm, ntens, stran, dstran, stress, statev, &
                                       ddsdde, res)
      class(model_type), intent(in) :: model
      real(dp), intent(in) :: dt
      integer, intent(in) :: perm(6), ntens
      real(dp), intent(in) :: stran(ntens), dstran(ntens)
      real(dp), intent(inout) :: stress(ntens), statev(:)
      real(dp), intent(out) :: ddsdde(ntens, ntens)
      type(upf_result), intent(out) :: res
      real(dp) :: eps0(6), deps(6), y0(model%n_state()), y(model%n_state()), sig(6), sig0(6)
      real(dp) :: c(6, 6), g, k, dein(6)
      integer :: pos(6), i, status, nsub, b
      integer, allocatable :: y_first(:), code_first(:), kind(:)
      call upf_elastic_tangent([model%youngs, model%poisson], perm, ntens, ddsdde)
      res%status = upf_invalid
      if (ntens /= 6 .and. ntens /= 4 .and. ntens /= 3) then
         write (res%message, '(a,i0,a)') 'elements with ', ntens, &
            ' stress components are not supported (6: 3-D, 4: plane strain or axisymmetric, '// &
            '3: plane stress)'
         return
      end if
      res%status = upf_cut
      pos = positions(perm, ntens)
      ! Code order, engineering shear -> Mandel; absent components are zero
      eps0 = 0.0_dp
      deps = 0.0_dp
      do i = 1, 6
         if (pos(i) > 0) then
            eps0(i) = stran(pos(i))*merge(1.0_dp, 1.0_dp/s2, i <= 3)
            deps(i) = dstran(pos(i))*merge(1.0_dp, 1.0_dp/s2, i <= 3)
         end if
      end do
      ! The model's state from the code's: tensors to Mandel form, block by block
      call model%fe_layout(y_first, code_first, kind)
      do b = 1, size(kind)
         associate (yf => y_first(b), cf => code_first(b))
            select case (kind(b))
            case (block_strain)
               do i = 1, 6
                  y0(yf - 1 + i) = statev(cf - 1 + perm(i))*merge(1.0_dp, 1.0_dp/s2, i <= 3)
               end do
            case (block_stress)
               do i = 1, 6
                  y0(yf - 1 + i) = statev(cf - 1 + perm(i))*w_mandel(i)
               end do
            case default
               y0(yf) = statev(cf)
            end select
         end associate
      end do
      call model%complete_state(y0)
      call elastic_moduli(model%youngs, model%poisson, g, k)
      if (ntens == 3) then
         call plane_stress_update(model, g, k, dt, y0, eps0, deps, sig, y, c, status)
      else
         call model%stress_update(eps0, deps, dt, y0, sig, y, c, status, nsub)
      end if
      if (status /= update_status_ok) return
      res%status = upf_ok
      ! Energies: the elastic one at the end; the inelastic work by the trapezoid rule, so that
      ! with the same rule for the external work of the increments the balance closes exactly
      sig0 = elastic_stress(g, k, eps0, y0(1:6))
      dein = y(1:6) - y0(1:6)
      res%sse = 0.5_dp*dot_product(sig, eps0 + deps - y(1:6))
      res%dspd = 0.5_dp*dot_product(sig0 + sig, dein)
      res%deqin = sqrt(2.0_dp/3.0_dp*dot_product(dein, dein))
      res%eps33 = eps0(3) + deps(3)
      do i = 1, 6
         if (pos(i) > 0) stress(pos(i)) = sig(i)/w_mandel(i)
      end do
      do b = 1, size(kind)
         associate (yf => y_first(b), cf => code_first(b))
            select case (kind(b))
            case (block_strain)
               do i = 1, 6
                  statev(cf - 1 + perm(i)) = y(yf - 1 + i)*merge(1.0_dp, s2, i <= 3)
               end do
            case (block_stress)
               do i = 1, 6
                  statev(cf - 1 + perm(i)) = y(yf - 1 + i)/w_mandel(i)
               end do
            case default
               statev(cf) = y(yf)
            end select
         end associate
      end do
      call tangent_to_code(c, pos, ntens, ddsdde)
   end subroutine upf_update_material

   !> Stress from total and inelastic strain (Mandel)
   pure function elastic_stress(g, k, eps, ein) result(sig)
      real(dp), intent(in) :: g, k, eps(6), ein(6)
      real(dp) :: sig(6), tr
      tr = sum(eps(1:3))
      sig = 2.0_dp*(g*(eps - ein))
      sig(1:3) = sig(1:3) + (k - 2.0_dp*g/3.0_dp)*tr
   end function elastic_stress

   !> Plane stress: the 3-D update with the out-of-plane strain found by Newton's method on
   !> s33 = 0 with the consistent tangent. eps0(3) and deps(3) come in as zero and leave as
   !> the solution: the start value from s33 = 0 at the start state, exactly, the increment
   !> from the elastic guess on.
   pure subroutine plane_stress_update(model, g, k, dt, y0, eps0, deps, sig, y, c, status)
      class(model_type), intent(in) :: model
      real(dp), intent(in) :: g, k, dt, y0(:)
      real(dp), intent(inout) :: eps0(6), deps(6)
      real(dp), intent(out) :: sig(6), y(:), c(6, 6)
      integer, intent(out) :: status
      real(dp) :: lam, stiff33, tol
      integer :: it, nsub
      lam = k - 2.0_dp*g/3.0_dp
      stiff33 = k + 4.0_dp*g/3.0_dp
      ! s33 = stiff33 e33 + lam (e11 + e22) - 2G ein33 = 0 (the inelastic strain is deviatoric)
      eps0(3) = (2.0_dp*g*y0(3) - lam*(eps0(1) + eps0(2)))/stiff33
      deps(3) = (2.0_dp*g*y0(3) - lam*(eps0(1) + deps(1) + eps0(2) + deps(2)))/stiff33 - eps0(3)
      status = update_status_cut
      do it = 1, max_plane_stress_iterations
         call model%stress_update(eps0, deps, dt, y0, sig, y, c, status, nsub)
         if (status /= update_status_ok) return
         tol = tol_plane_stress*max(maxval(abs(sig)), 1.0e-3_dp*model%youngs)
         if (abs(sig(3)) <= tol) return
         deps(3) = deps(3) - sig(3)/c(3, 3)
      end do
      status = update_status_cut
   end subroutine plane_stress_update
end module usharp_upf
