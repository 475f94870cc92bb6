!> What the 3-D J2 stress updates of the models share: Mandel vectors (11, 22, 33,
!> sqrt2*12, sqrt2*23, sqrt2*13, so that double contractions are dot products), the
!> deviatoric projector, a small dense solver, and j2_model: a model whose update is backward
!> Euler in substeps, which shares the substepping, the stress and the consistent tangent and
!> supplies the local step.
!> The local systems are solved in place rather than through LAPACK, so that a drop-in user
!> material links into an FE code without a LAPACK library.
module usharp_model_j2
   use usharp_kinds, only: dp
   use usharp_model, only: model_type, elastic_moduli, update_status_ok, update_status_cut
   implicit none
   private

   public :: deviator_projector, solve_dense, m_vec, j2_model

   !> The second-order identity in Mandel form
   real(dp), parameter :: m_vec(6) = [1.0_dp, 1.0_dp, 1.0_dp, 0.0_dp, 0.0_dp, 0.0_dp]
   !> Halvings of the substeps before an update gives up
   integer, parameter :: max_halvings = 12

   !> A model whose 3-D state starts with the inelastic strain (y(1:6), Mandel) and whose
   !> stress update is backward Euler in substeps: the stress is the elastic law on the strain
   !> less the inelastic strain, and the consistent tangent follows from the sensitivity of
   !> the inelastic strain to the increment's end strain, carried through the substeps.
   type, abstract, extends(model_type) :: j2_model
   contains
      !> Backward Euler on one substep
      procedure(local_step_sub), deferred :: local_step
      procedure :: stress_update => j2_stress_update
   end type j2_model

   abstract interface
      !> Backward Euler on one substep from yprev to the total strain eps (Mandel) at its end
      !> over dt (s), with the shear modulus g and the deviatoric projector p; frac is the
      !> share of the increment reached at its end and dyde_prev the sensitivity of yprev to
      !> the increment's end strain; y and dyde return the same at the end. status:
      !> update_status_ok, or update_status_cut where the step fails
      pure subroutine local_step_sub(self, g, p, eps, yprev, dt, frac, dyde_prev, y, dyde, status)
         import :: j2_model, dp
         class(j2_model), intent(in) :: self
         real(dp), intent(in) :: g, p(6, 6), eps(6), dt, frac
         real(dp), intent(in), contiguous :: yprev(:), dyde_prev(:, :)
         real(dp), intent(out), contiguous :: y(:), dyde(:, :)
         integer, intent(out) :: status
      end subroutine local_step_sub
   end interface

contains

   !> Deviatoric projector in Mandel form
   pure function deviator_projector() result(p)
      real(dp) :: p(6, 6)
      integer :: i
      p = -spread(m_vec, 1, 6)*spread(m_vec, 2, 6)/3.0_dp
      do i = 1, 6
         p(i, i) = p(i, i) + 1.0_dp
      end do
   end function deviator_projector

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

   !> The stress update of model_type over one increment in update_substeps (or nsubsteps)
   !> equal substeps of the strain, linear in time, doubled up to max_halvings times while a
   !> substep fails; when all fail y = y0, sigma and ddsde are the elastic trial and status
   !> = update_status_cut
   pure subroutine j2_stress_update(self, eps0, deps, dt, y0, sigma, y, ddsde, status, nsub, &
                                    nsubsteps)
      class(j2_model), intent(in) :: self
      real(dp), intent(in) :: eps0(6), deps(6), dt, y0(:)
      real(dp), intent(out) :: sigma(6), y(:), ddsde(6, 6)
      integer, intent(out) :: status, nsub
      integer, intent(in), optional :: nsubsteps
      real(dp) :: dyde(size(y0), 6), ycur(size(y0)), ynew(size(y0)), dydecur(size(y0), 6)
      real(dp) :: g, k, frac, p(6, 6)
      integer :: base, level, i, isub, st
      logical :: ok
      call elastic_moduli(self%youngs, self%poisson, g, k)
      p = deviator_projector()
      status = update_status_cut
      nsub = 0
      base = self%update_substeps()
      if (present(nsubsteps)) base = max(1, nsubsteps)
      do level = 0, max_halvings
         nsub = base*2**level
         ycur = y0
         dydecur = 0.0_dp
         ok = .true.
         do isub = 1, nsub
            frac = real(isub, dp)/real(nsub, dp)
            call self%local_step(g, p, eps0 + frac*deps, ycur, dt/nsub, frac, dydecur, ynew, &
                                 dyde, st)
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
         ycur = y0
         dydecur = 0.0_dp
      end if
      y = ycur
      sigma = 2.0_dp*g*(matmul(p, eps0 + deps) - y(1:6)) + k*sum((eps0 + deps)*m_vec)*m_vec
      ddsde = 2.0_dp*g*p + k*spread(m_vec, 1, 6)*spread(m_vec, 2, 6)
      do i = 1, 6
         ddsde(:, i) = ddsde(:, i) - 2.0_dp*g*dydecur(1:6, i)
      end do
   end subroutine j2_stress_update
end module usharp_model_j2
