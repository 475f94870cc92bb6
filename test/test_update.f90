!> Tests of the implicit stress update and the single-element (umat) driver
module test_update
   use testdrive, only: error_type, unittest_type, new_unittest, check, test_failed
   use usharp_kinds, only: dp
   use usharp_error, only: uerror => error_type
   use usharp_miller, only: miller_model, model_setup
   use usharp_miller_update, only: miller_update, n_state, update_status_ok
   use usharp_history, only: history_type, output_times
   use usharp_simulation, only: solver_options, sim_result
   use usharp_cvode_driver, only: simulate_cvode
   use usharp_umat_driver, only: simulate_umat
   use test_driver, only: thesis_test
   implicit none
   private
   public :: collect_update

   real(dp), parameter :: s2 = sqrt(2.0_dp)

contains

   subroutine collect_update(testsuite)
      type(unittest_type), allocatable, intent(out) :: testsuite(:)
      testsuite = [ &
         new_unittest('tangent-fd-elastic', test_tangent_elastic), &
         new_unittest('tangent-fd-strongly-inelastic', test_tangent_inelastic), &
         new_unittest('umat-matches-cvode-thesis-tests', test_umat_vs_cvode), &
         new_unittest('umat-first-order-convergence', test_order)]
   end subroutine collect_update

   !> Largest relative difference between the tangent and central differences of the update
   subroutine tangent_check(error, m, eps0, deps, dt, y0)
      type(error_type), allocatable, intent(out) :: error
      type(miller_model), intent(in) :: m
      real(dp), intent(in) :: eps0(6), deps(6), dt, y0(n_state)
      real(dp) :: sig(6), y(n_state), c(6, 6), fd(6, 6), sp(6), sm(6), cdum(6, 6), d(6), hstep, dev
      integer :: j, st, nsub
      character(len=100) :: buf
      call miller_update(m, eps0, deps, dt, y0, sig, y, c, st, nsub)
      if (st /= update_status_ok) then
         call test_failed(error, 'update did not converge')
         return
      end if
      hstep = 1.0e-7_dp
      do j = 1, 6
         d = 0.0_dp
         d(j) = hstep
         call miller_update(m, eps0, deps + d, dt, y0, sp, y, cdum, st, nsub)
         call miller_update(m, eps0, deps - d, dt, y0, sm, y, cdum, st, nsub)
         fd(:, j) = (sp - sm)/(2*hstep)
      end do
      dev = maxval(abs(c - fd))/maxval(abs(fd))
      write (buf, '(a,es10.3,a,es12.4,a,es12.4)') 'max |C - FD| / max |FD| = ', dev, '; C11 ', c(1, 1), &
         ' FD ', fd(1, 1)
      call check(error, dev <= 1.0e-6_dp, trim(buf))
   end subroutine tangent_check

   subroutine test_tangent_elastic(error)
      type(error_type), allocatable, intent(out) :: error
      type(miller_model) :: m
      type(uerror), allocatable :: uerr
      real(dp) :: y0(n_state)
      call model_setup(m, uerr)
      y0 = 0.0_dp
      y0(13) = m%d0
      call tangent_check(error, m, [1.0e-5_dp, -3.0e-6_dp, -3.0e-6_dp, 0.0_dp, 0.0_dp, 0.0_dp], &
                         [2.0e-5_dp, -6.0e-6_dp, -6.0e-6_dp, s2*1e-6_dp, 0.0_dp, s2*2e-6_dp], 0.1_dp, y0)
   end subroutine test_tangent_elastic

   subroutine test_tangent_inelastic(error)
      type(error_type), allocatable, intent(out) :: error
      type(miller_model) :: m
      type(uerror), allocatable :: uerr
      real(dp) :: y0(n_state), ein(6), r(6)
      call model_setup(m, uerr)
      ! After tensile yielding: inelastic strain 0.3 %, back stress 8 ksi, D 11.5 ksi; the
      ! increment drives the overstress past the knee of the sinh law, with shear
      ein = 0.003_dp*[1.0_dp, -0.5_dp, -0.5_dp, 0.0_dp, 0.0_dp, 0.0_dp]
      r = 8.0_dp*[2.0_dp/3, -1.0_dp/3, -1.0_dp/3, 0.0_dp, 0.0_dp, 0.0_dp]
      y0 = [ein, r, 11.5_dp]
      call tangent_check(error, m, ein + [8.0e-4_dp, -2.4e-4_dp, -2.4e-4_dp, 0.0_dp, 0.0_dp, 0.0_dp], &
                         [2.0e-4_dp, -9.0e-5_dp, -9.0e-5_dp, s2*4e-5_dp, s2*1e-5_dp, 0.0_dp], 0.15_dp, y0)
   end subroutine test_tangent_inelastic

   subroutine test_umat_vs_cvode(error)
      type(error_type), allocatable, intent(out) :: error
      type(miller_model) :: m
      type(history_type) :: h
      type(sim_result) :: ru, rc
      type(solver_options) :: opts
      type(uerror), allocatable :: uerr
      real(dp), allocatable :: tout(:)
      real(dp) :: dev
      integer :: k
      character(len=100) :: buf
      call model_setup(m, uerr)
      do k = 1, 3
         call thesis_test(k, h)
         tout = output_times(h, 1.0_dp)
         call simulate_cvode(m, h, tout, opts, rc, uerr)
         call simulate_umat(m, h, tout, opts, ru, uerr)
         if (allocated(uerr)) then
            call test_failed(error, uerr%message)
            return
         end if
         dev = maxval(abs(ru%stress - rc%stress))/maxval(abs(rc%stress))
         write (buf, '(a,i0,a,es10.3,a,i0,a)') 'test ', k, ': max |umat - cvode| / peak = ', dev, &
            ' (', ru%nsteps, ' increments)'
         call check(error, dev <= 5.0e-3_dp, trim(buf))
         if (allocated(error)) return
      end do
   end subroutine test_umat_vs_cvode

   !> Backward Euler is first order: halving dt_max halves the error against a tight reference
   subroutine test_order(error)
      type(error_type), allocatable, intent(out) :: error
      type(miller_model) :: m
      type(history_type) :: h
      type(sim_result) :: ru, rc
      type(solver_options) :: opts, tight
      type(uerror), allocatable :: uerr
      real(dp), allocatable :: tout(:)
      real(dp) :: err(3), dts(3)
      integer :: k
      character(len=120) :: buf
      call model_setup(m, uerr)
      tight%rtol = 1.0e-11_dp
      tight%atol_strain = 1.0e-15_dp
      call thesis_test(1, h)
      tout = output_times(h, 1.0_dp)
      call simulate_cvode(m, h, tout, tight, rc, uerr)
      dts = [0.2_dp, 0.1_dp, 0.05_dp]
      do k = 1, 3
         opts%dt_max = dts(k)
         opts%dt_init = dts(k)
         call simulate_umat(m, h, tout, opts, ru, uerr)
         err(k) = maxval(abs(ru%stress - rc%stress))/maxval(abs(rc%stress))
      end do
      write (buf, '(a,3es10.3,a,2f6.2)') 'errors ', err, '; ratios ', err(1)/err(2), err(2)/err(3)
      call check(error, all([err(1)/err(2), err(2)/err(3)] > 1.7_dp) .and. &
                 all([err(1)/err(2), err(2)/err(3)] < 2.3_dp), 'first order: '//trim(buf))
   end subroutine test_order
end module test_update
