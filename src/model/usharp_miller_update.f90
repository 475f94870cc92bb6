!> Implicit (backward Euler) small-strain J2 stress update of the Miller model, in the style of
!> a UMAT: given the strain at the start of an increment, the strain increment, the time step
!> and the state, return the stress, the new state and the consistent tangent.
!>
!> Tensors are 6-vectors in Mandel form (11, 22, 33, sqrt2*12, sqrt2*23, sqrt2*13), so that
!> double contractions are dot products; the FE adapters convert to Voigt order and
!> engineering shear. State y = (inelastic strain (6), back stress R (6), drag stress D).
!> The multiaxial form (Kagawa and Asada 1983): with S = dev(sigma) - R, x = sqrt(3/2 S:S),
!> r = sqrt(3/2 R:R), f = flow_rate(x, D):
!>    d(eps_in)/dt = 3/2 f S/x,   dR/dt = H1 f S/x - g(r) R/r,   dD/dt = H2 f (C2 + r - A2/A1 D^3) - h(D)
!> which reduces to Eqs. 2-4 in uniaxial stress. It uses the same rate kernels as the CVODE path.
module usharp_miller_update
   use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
   use usharp_kinds, only: dp
   use usharp_miller, only: miller_model, rate_terms, rate_terms_at
   implicit none
   private

   public :: miller_update, update_status_ok, update_status_cut, n_state, elastic_moduli
   public :: deviator_projector

   !> Number of state variables: inelastic strain (6), back stress (6), drag stress
   integer, parameter :: n_state = 13
   !> Outcome: converged, or the caller must retry with a smaller increment
   integer, parameter :: update_status_ok = 0, update_status_cut = 1
   !> Newton iterations per (sub)increment and halvings of the increment before giving up
   integer, parameter :: max_newton = 25, max_halvings = 12
   !> Backward Euler substeps per increment: the increments of an FE solution (0.15 s in the
   !> thesis's deck) are too coarse for first-order accuracy across the knee of the sinh law
   integer, parameter, public :: default_substeps = 8
   real(dp), parameter :: m_vec(6) = [1.0_dp, 1.0_dp, 1.0_dp, 0.0_dp, 0.0_dp, 0.0_dp]
   ! The local systems are solved in place (13 unknowns) rather than through LAPACK, so that
   ! the drop-in user material links into an FE code without a LAPACK library

contains

   !> Shear and bulk moduli from E and Poisson's ratio
   elemental subroutine elastic_moduli(model, g, k)
      type(miller_model), intent(in) :: model
      real(dp), intent(out) :: g, k
      g = model%youngs/(2.0_dp*(1.0_dp + model%poisson))
      k = model%youngs/(3.0_dp*(1.0_dp - 2.0_dp*model%poisson))
   end subroutine elastic_moduli

   !> Deviatoric projector in Mandel form
   pure function deviator_projector() result(p)
      real(dp) :: p(6, 6)
      integer :: i
      p = -spread(m_vec, 1, 6)*spread(m_vec, 2, 6)/3.0_dp
      do i = 1, 6
         p(i, i) = p(i, i) + 1.0_dp
      end do
   end function deviator_projector

   !> Stress update over one increment. eps0: strain at the start, deps: its increment,
   !> dt: time step (s), y0: state at the start (Mandel; D > 0). On success status is
   !> update_status_ok; otherwise sigma, y and ddsde are unchanged from the elastic trial and
   !> status = update_status_cut asks the caller for a smaller increment.
   !> The increment is integrated in substeps (default_substeps equal ones, or nsubsteps);
   !> nsub returns how many were used (more when Newton needed halvings).
   pure subroutine miller_update(model, eps0, deps, dt, y0, sigma, y, ddsde, status, nsub, nsubsteps)
      type(miller_model), intent(in) :: model
      real(dp), intent(in) :: eps0(6), deps(6), dt, y0(n_state)
      real(dp), intent(out) :: sigma(6), y(n_state), ddsde(6, 6)
      integer, intent(out) :: status, nsub
      integer, intent(in), optional :: nsubsteps
      integer :: base
      real(dp) :: dyde(n_state, 6), ycur(n_state), ynew(n_state), dydecur(n_state, 6), g, k, frac
      real(dp) :: p(6, 6)
      integer :: level, i, isub, st
      logical :: ok

      call elastic_moduli(model, g, k)
      p = deviator_projector()
      status = update_status_cut
      nsub = 0
      base = default_substeps
      if (present(nsubsteps)) base = max(1, nsubsteps)
      ! Try base substeps, then 2, 4, ... times as many (strain linear in time)
      do level = 0, max_halvings
         nsub = base*2**level
         ycur = y0
         dydecur = 0.0_dp
         ok = .true.
         do isub = 1, nsub
            frac = real(isub, dp)/real(nsub, dp)
            call local_newton(model, g, p, eps0 + frac*deps, ycur, dt/nsub, frac, dydecur, &
                              ynew, dyde, st)
            if (st /= update_status_ok) then
               ok = .false.
               exit
            end if
            ycur = ynew
            dydecur = dyde
         end do
         if (ok) then
            status = update_status_ok
            exit
         end if
      end do
      if (status /= update_status_ok) then
         y = y0
         ycur = y0
         dydecur = 0.0_dp
      else
         y = ycur
      end if
      sigma = 2.0_dp*g*(matmul(p, eps0 + deps) - y(1:6)) + k*sum((eps0 + deps)*m_vec)*m_vec
      ddsde = 2.0_dp*g*p + k*spread(m_vec, 1, 6)*spread(m_vec, 2, 6)
      do i = 1, 6
         ddsde(:, i) = ddsde(:, i) - 2.0_dp*g*dydecur(1:6, i)
      end do
   end subroutine miller_update

   !> Backward Euler on one subincrement by Newton's method with the analytic Jacobian.
   !> frac is the share of the whole strain increment reached at its end, dyde_prev the
   !> sensitivity of the starting state to the end strain of the whole increment; dyde
   !> returns the same for the new state (chain rule across subincrements).
   pure subroutine local_newton(model, g, p, eps, yprev, dt, frac, dyde_prev, y, dyde, status)
      type(miller_model), intent(in) :: model
      real(dp), intent(in) :: g, p(6, 6), eps(6), yprev(n_state), dt, frac, dyde_prev(n_state, 6)
      real(dp), intent(out) :: y(n_state), dyde(n_state, 6)
      integer, intent(out) :: status
      real(dp) :: r(n_state), jac(n_state, n_state), drde(n_state, 6), dy(n_state, 1)
      real(dp) :: tol_strain, tol_stress, scale_s
      integer :: it, info
      status = update_status_cut
      y = yprev
      scale_s = max(maxval(abs(yprev(7:13))), 1.0e-3_dp*model%youngs)
      tol_strain = 1.0e-13_dp + 1.0e-11_dp*maxval(abs(yprev(1:6)))
      tol_stress = 1.0e-11_dp*scale_s
      do it = 1, max_newton
         call residual(model, g, p, eps, yprev, dt, y, r, jac, drde)
         if (.not. all(ieee_is_finite(r)) .or. .not. all(ieee_is_finite(jac))) return
         dy(:, 1) = -r
         call solve_dense(jac, dy, info)
         if (info /= 0 .or. .not. all(ieee_is_finite(dy))) return
         y = y + dy(:, 1)
         if (y(13) <= 0.0_dp) return
         if (maxval(abs(dy(1:6, 1))) <= tol_strain .and. maxval(abs(dy(7:13, 1))) <= tol_stress) then
            ! Converged: the sensitivity by the implicit function theorem at the solution,
            ! d r/d y * dy/de = -(d r/d eps * frac - dyde_prev)
            call residual(model, g, p, eps, yprev, dt, y, r, jac, drde)
            dyde = dyde_prev - frac*drde
            call solve_dense(jac, dyde, info)
            if (info /= 0 .or. .not. all(ieee_is_finite(dyde))) return
            status = update_status_ok
            return
         end if
      end do
   end subroutine local_newton

   !> Residual of backward Euler r(y) = y - yprev - dt*rates(y), its Jacobian d r/d y and
   !> its derivative with respect to the total strain at the end of the step
   pure subroutine residual(model, g, p, eps, yprev, dt, y, r, jac, drde)
      type(miller_model), intent(in) :: model
      real(dp), intent(in) :: g, p(6, 6), eps(6), yprev(n_state), dt, y(n_state)
      real(dp), intent(out) :: r(n_state), jac(n_state, n_state), drde(n_state, 6)
      real(dp) :: s(6), nh(6), mh(6), x, rb, d, f, f_x, f_d, gr, gr_r, h, h_d, w, a
      type(rate_terms) :: t
      real(dp) :: phi(6), psi(6), dphi(6, 6), dpsi(6, 6), fx_over, g_over, eye(6, 6)
      integer :: i
      eye = 0.0_dp
      do i = 1, 6
         eye(i, i) = 1.0_dp
      end do
      s = 2.0_dp*g*(matmul(p, eps) - y(1:6)) - y(7:12)
      x = sqrt(1.5_dp*dot_product(s, s))
      rb = sqrt(1.5_dp*dot_product(y(7:12), y(7:12)))
      d = y(13)
      t = rate_terms_at(model, x, rb, d)
      f = t%f; f_x = t%f_x; f_d = t%f_d
      gr = t%g; gr_r = t%g_r
      h = t%h; h_d = t%h_d
      w = t%w; a = t%a
      ! Unit directions and their derivatives; at x = 0 (or r = 0) the limits are used
      if (x > 0.0_dp) then
         nh = s/x
         fx_over = f/x
      else
         nh = 0.0_dp
         fx_over = 0.0_dp
      end if
      if (rb > 0.0_dp) then
         mh = y(7:12)/rb
         g_over = gr/rb
      else
         mh = 0.0_dp
         g_over = gr_r
      end if
      phi = f*nh
      psi = gr*mh
      dphi = 1.5_dp*(f_x - fx_over)*spread(nh, 2, 6)*spread(nh, 1, 6) + fx_over*eye
      dpsi = 1.5_dp*(gr_r - g_over)*spread(mh, 2, 6)*spread(mh, 1, 6) + g_over*eye

      r(1:6) = y(1:6) - yprev(1:6) - dt*1.5_dp*phi
      r(7:12) = y(7:12) - yprev(7:12) - dt*(model%c%h1*phi - psi)
      r(13) = y(13) - yprev(13) - dt*(model%c%h2*f*w - h)

      ! dS/d(eps_in) = -2G I, dS/dR = -I, dS/d(eps) = 2G P
      jac(1:6, 1:6) = eye + 3.0_dp*g*dt*dphi
      jac(1:6, 7:12) = 1.5_dp*dt*dphi
      jac(1:6, 13) = -1.5_dp*dt*f_d*nh
      jac(7:12, 1:6) = 2.0_dp*g*dt*model%c%h1*dphi
      jac(7:12, 7:12) = eye + dt*model%c%h1*dphi + dt*dpsi
      jac(7:12, 13) = -dt*model%c%h1*f_d*nh
      jac(13, 1:6) = 3.0_dp*g*dt*model%c%h2*w*f_x*nh
      jac(13, 7:12) = -dt*(-1.5_dp*model%c%h2*w*f_x*nh + 1.5_dp*model%c%h2*f*mh)
      jac(13, 13) = 1.0_dp - dt*(model%c%h2*(f_d*w - 3.0_dp*a*f*d**2) - h_d)

      drde(1:6, :) = -3.0_dp*g*dt*matmul(dphi, p)
      drde(7:12, :) = -2.0_dp*g*dt*model%c%h1*matmul(dphi, p)
      drde(13, :) = -3.0_dp*g*dt*model%c%h2*w*f_x*matmul(nh, p)
   end subroutine residual

   !> Solve a x = b (b overwritten by x) by Gaussian elimination with partial pivoting;
   !> info = 1 when a pivot is zero (a singular matrix)
   pure subroutine solve_dense(a, b, info)
      real(dp), intent(in) :: a(:, :)
      real(dp), intent(inout) :: b(:, :)
      integer, intent(out) :: info
      real(dp) :: lu(size(a, 1), size(a, 2)), row(size(a, 2)), rhs(size(b, 2)), f
      integer :: n, i, k, piv
      n = size(a, 1)
      lu = a
      info = 1
      do k = 1, n
         piv = k - 1 + maxloc(abs(lu(k:n, k)), 1)
         if (.not. abs(lu(piv, k)) > 0.0_dp) return  ! also a NaN
         if (piv /= k) then
            row = lu(k, :)
            lu(k, :) = lu(piv, :)
            lu(piv, :) = row
            rhs = b(k, :)
            b(k, :) = b(piv, :)
            b(piv, :) = rhs
         end if
         do i = k + 1, n
            f = lu(i, k)/lu(k, k)
            lu(i, k + 1:n) = lu(i, k + 1:n) - f*lu(k, k + 1:n)
            b(i, :) = b(i, :) - f*b(k, :)
         end do
      end do
      do k = n, 1, -1
         b(k, :) = (b(k, :) - matmul(lu(k, k + 1:n), b(k + 1:n, :)))/lu(k, k)
      end do
      info = 0
   end subroutine solve_dense
end module usharp_miller_update
