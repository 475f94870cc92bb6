!> Tests of the Miller model: theta, D0, rate Jacobian against finite differences, checks
module test_model
   use testdrive, only: error_type, unittest_type, new_unittest, check, test_failed
   use usharp_kinds, only: dp
   use usharp_error, only: uerror => error_type
   use test_util, only: check_message
   use usharp_model_miller, only: miller_model, theta_miller, model_setup, &
                            gas_constant, set_constant, constant_index
   implicit none
   private
   public :: collect_model

contains

   subroutine collect_model(testsuite)
      type(unittest_type), allocatable, intent(out) :: testsuite(:)
      testsuite = [ &
         new_unittest('theta-both-branches', test_theta), &
         new_unittest('d0-table4', test_d0), &
         new_unittest('jacobian-fd-strain-control', test_jac_strain), &
         new_unittest('jacobian-fd-stress-control', test_jac_stress), &
         new_unittest('rates-sign-symmetry', test_symmetry), &
         new_unittest('rates-at-the-ends-of-the-power-laws', test_rate_ends), &
         new_unittest('constant-checks-name-the-constant', test_checks)]
   end subroutine collect_model

   subroutine test_theta(error)
      type(error_type), allocatable, intent(out) :: error
      real(dp) :: q, tm, t, expect
      ! Thesis value at 593 C with Q = 91000 cal/mol, Tm = 1800 K (low branch, T < 0.6 Tm)
      call check(error, theta_miller(91000.0_dp, 1800.0_dp, 866.15_dp), 3.217e-23_dp, &
                 'theta at 593 C', thr=2.0e-4_dp, rel=.true.)
      if (allocated(error)) return
      ! High branch by hand: exp(-Q/(k T)) at T = 1200 K > 0.6*1800
      q = 91000.0_dp; tm = 1800.0_dp; t = 1200.0_dp
      expect = exp(-q/(gas_constant*t))
      call check(error, theta_miller(q, tm, t), expect, 'theta above 0.6 Tm', thr=1e-14_dp, rel=.true.)
      if (allocated(error)) return
      ! Continuity at T = 0.6 Tm: both branches give exp(-Q/(0.6 k Tm))
      call check(error, theta_miller(q, tm, 0.6_dp*tm), exp(-q/(0.6_dp*gas_constant*tm)), &
                 'theta at 0.6 Tm', thr=1e-13_dp, rel=.true.)
      if (allocated(error)) return
      call check(error, theta_miller(q, tm, 0.6_dp*tm*(1 + 1e-9_dp)), &
                 theta_miller(q, tm, 0.6_dp*tm*(1 - 1e-9_dp)), 'theta continuous', thr=1e-6_dp, rel=.true.)
   end subroutine test_theta

   subroutine test_d0(error)
      type(error_type), allocatable, intent(out) :: error
      type(miller_model) :: m
      type(uerror), allocatable :: uerr
      call model_setup(m, uerr)
      call check(error, .not. allocated(uerr), 'Table 4 constants accepted')
      if (allocated(error)) return
      call check(error, m%d0, 11.062_dp, 'D0 for Table 4 (thesis 11.062 ksi)', thr=1e-3_dp)
      if (allocated(error)) return
      m%d0_fixed = 9.5_dp
      call model_setup(m, uerr)
      call check(error, m%d0, 9.5_dp, 'fixed D0 is used')
   end subroutine test_d0

   !> Largest relative difference between the analytic Jacobian and central differences
   subroutine jac_check(error, m, sigma_of, dsig, y)
      type(error_type), allocatable, intent(out) :: error
      type(miller_model), intent(in) :: m
      interface
         pure real(dp) function sigma_of(eps_in)
            import :: dp
            real(dp), intent(in) :: eps_in
         end function sigma_of
      end interface
      real(dp), intent(in) :: dsig, y(3)
      real(dp) :: jac(3, 3), fd(3, 3), f0(3), fp(3), fm(3), yp(3), ym(3), h, scale
      integer :: j
      character(len=120) :: buf
      call m%uniaxial_rates(sigma_of(y(1)), dsig, y, f0, jac)
      do j = 1, 3
         h = 1.0e-6_dp*max(abs(y(j)), merge(1.0e-3_dp, 1.0_dp, j == 1))
         yp = y; ym = y
         yp(j) = y(j) + h
         ym(j) = y(j) - h
         call m%uniaxial_rates(sigma_of(yp(1)), dsig, yp, fp)
         call m%uniaxial_rates(sigma_of(ym(1)), dsig, ym, fm)
         fd(:, j) = (fp - fm)/(2*h)
      end do
      do j = 1, 3
         scale = maxval(abs(fd(j, :)*[1.0e-3_dp, 1.0_dp, 1.0_dp]))
         if (scale == 0.0_dp) cycle
         if (maxval(abs(jac(j, :) - fd(j, :))*[1.0e-3_dp, 1.0_dp, 1.0_dp])/scale > 1.0e-6_dp) then
            write (buf, '(a,i0,a,3es12.4,a,3es12.4)') 'row ', j, ': analytic ', jac(j, :), ' fd ', fd(j, :)
            call test_failed(error, trim(buf))
            return
         end if
      end do
   end subroutine jac_check

   subroutine test_jac_strain(error)
      type(error_type), allocatable, intent(out) :: error
      type(miller_model) :: m
      type(uerror), allocatable :: uerr
      real(dp), parameter :: eps_tot(3) = [0.004_dp, -0.0045_dp, 0.0009_dp]
      real(dp), parameter :: states(3, 3) = reshape([ &
         0.0032_dp, 8.0_dp, 11.5_dp, &      ! strongly inelastic, tension
         -0.0036_dp, -9.0_dp, 12.0_dp, &    ! strongly inelastic, compression
         0.0001_dp, 1.5_dp, 11.06_dp], [3, 3])  ! near elastic
      integer :: k
      call model_setup(m, uerr)
      do k = 1, 3
         call jac_check(error, m, sig_k, -m%youngs, states(:, k))
         if (allocated(error)) return
      end do
   contains
      pure real(dp) function sig_k(eps_in)
         real(dp), intent(in) :: eps_in
         sig_k = 22.5e3_dp*(eps_tot(k) - eps_in)
      end function sig_k
   end subroutine test_jac_strain

   subroutine test_jac_stress(error)
      type(error_type), allocatable, intent(out) :: error
      type(miller_model) :: m
      type(uerror), allocatable :: uerr
      call model_setup(m, uerr)
      call jac_check(error, m, sig_const, 0.0_dp, [0.002_dp, 6.0_dp, 11.3_dp])
   contains
      pure real(dp) function sig_const(eps_in)
         real(dp), intent(in) :: eps_in
         sig_const = 17.0_dp + 0.0_dp*eps_in
      end function sig_const
   end subroutine test_jac_stress

   subroutine test_symmetry(error)
      type(error_type), allocatable, intent(out) :: error
      type(miller_model) :: m
      type(uerror), allocatable :: uerr
      real(dp) :: fp(3), fm(3)
      call model_setup(m, uerr)
      call m%uniaxial_rates(20.0_dp, -m%youngs, [0.001_dp, 5.0_dp, 11.0_dp], fp)
      call m%uniaxial_rates(-20.0_dp, -m%youngs, [-0.001_dp, -5.0_dp, 11.0_dp], fm)
      call check(error, fp(1), -fm(1), 'inelastic rate odd', thr=1e-14_dp, rel=.true.)
      if (allocated(error)) return
      call check(error, fp(2), -fm(2), 'back-stress rate odd', thr=1e-14_dp, rel=.true.)
      if (allocated(error)) return
      call check(error, fp(3), fm(3), 'drag rate even', thr=1e-14_dp, rel=.true.)
      if (allocated(error)) return
      call check(error, fp(1) > 0.0_dp, 'flow in the direction of the overstress')
   end subroutine test_symmetry

   !> The power laws' special cases: no flow at zero overstress, none finite far beyond the
   !> drag stress (z > 700) or from a NaN stress (the integrator then shortens the step; a
   !> zero flow there would hide it)
   subroutine test_rate_ends(error)
      use, intrinsic :: ieee_arithmetic, only: ieee_is_finite, ieee_value, ieee_quiet_nan
      type(error_type), allocatable, intent(out) :: error
      type(miller_model) :: m
      type(uerror), allocatable :: uerr
      real(dp) :: f(3), jac(3, 3)
      call model_setup(m, uerr)
      call m%uniaxial_rates(5.0_dp, -m%youngs, [0.001_dp, 5.0_dp, 11.0_dp], f, jac)
      call check(error, f(1) == 0.0_dp .and. jac(1, 1) == 0.0_dp, 'no flow at zero overstress')
      if (allocated(error)) return
      call m%uniaxial_rates(1.0e4_dp, -m%youngs, [0.001_dp, 5.0_dp, 11.0_dp], f)
      call check(error, .not. ieee_is_finite(f(1)), 'flow not finite far beyond the drag stress')
      if (allocated(error)) return
      call m%uniaxial_rates(ieee_value(1.0_dp, ieee_quiet_nan), -m%youngs, [0.001_dp, 5.0_dp, 11.0_dp], f)
      call check(error, .not. ieee_is_finite(f(1)), 'flow not finite from a NaN stress')
   end subroutine test_rate_ends

   subroutine test_checks(error)
      type(error_type), allocatable, intent(out) :: error
      type(miller_model) :: m
      type(uerror), allocatable :: uerr
      m = miller_model()
      call set_constant(m%c, constant_index('H1'), -3.0_dp)
      call model_setup(m, uerr)
      call check_message(error, uerr, 'constant H1 must be > 0')
      if (allocated(error)) return
      m = miller_model()
      call set_constant(m%c, constant_index('n'), huge(1.0_dp)*0.0_dp + ieee_nan())
      call model_setup(m, uerr)
      call check_message(error, uerr, 'constant n is not finite')
      if (allocated(error)) return
      m = miller_model()
      m%temperature = 1800.0_dp
      call model_setup(m, uerr)
      call check_message(error, uerr, 'at or above Tm')
      if (allocated(error)) return
      m = miller_model()
      m%youngs = 0.0_dp
      call model_setup(m, uerr)
      call check_message(error, uerr, "Young's modulus E must be > 0")
      if (allocated(error)) return
      ! H1 so large that YS - 0.002*H1 < 0: D0 cannot be computed
      m = miller_model()
      m%c%h1 = 1.0e4_dp
      call model_setup(m, uerr)
      call check_message(error, uerr, 'initial drag stress D0')
   contains
      real(dp) function ieee_nan()
         use, intrinsic :: ieee_arithmetic, only: ieee_value, ieee_quiet_nan
         ieee_nan = ieee_value(1.0_dp, ieee_quiet_nan)
      end function ieee_nan
   end subroutine test_checks
end module test_model
