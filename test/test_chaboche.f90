!> Tests of the Chaboche model: constants, uniaxial rates and Jacobian, 3-D update and
!> consistent tangent, uniaxial form against the 3-D update, accuracy against a tight reference
module test_chaboche
   use testdrive, only: error_type, unittest_type, new_unittest, check, test_failed
   use usharp_kinds, only: dp
   use usharp_error, only: uerror => error_type
   use usharp_history, only: history_type, history_from_points, control_strain
   use usharp_simulation, only: solver_options, sim_result
   use usharp_cvode_driver, only: simulate_cvode
   use usharp_rosenbrock_driver, only: simulate_rosenbrock
   use usharp_umat_driver, only: simulate_umat
   use test_models, only: model_rates_jacobian, model_tangent
   use usharp_model_chaboche, only: chaboche_model, chaboche_setup, chaboche_uniaxial_rates, &
      chaboche_n_uniaxial, chaboche_n_state, chaboche_n_constants, &
      chaboche_get_constant, chaboche_set_constant, chaboche_constant_index, chaboche_constant_names, &
      chaboche_literature_low, chaboche_literature_high
   use usharp_model, only: update_status_ok
   implicit none
   private
   public :: collect_chaboche, test_chaboche_model, chaboche_uniaxial_rk4, chaboche_uniaxial_update

   integer, parameter :: nu = chaboche_n_uniaxial, ns = chaboche_n_state

contains

   subroutine collect_chaboche(testsuite)
      type(unittest_type), allocatable, intent(out) :: testsuite(:)
      testsuite = [ &
         new_unittest('constants-names-roundtrip', test_constants), &
         new_unittest('inadmissible-constants-rejected', test_setup_errors), &
         new_unittest('uniaxial-jacobian-fd', test_jacobian), &
         new_unittest('tangent-fd-inelastic-with-shear', test_tangent), &
         new_unittest('update-matches-uniaxial-rates', test_update_vs_rates), &
         new_unittest('update-first-order-and-1e-4-of-peak', test_accuracy), &
         new_unittest('drivers-within-1e-4-of-peak-of-tight-reference', test_drivers), &
         new_unittest('arrhenius-rates-scale-with-theta', test_arrhenius), &
         new_unittest('arrhenius-settings-checked', test_arrhenius_input)]
   end subroutine collect_chaboche

   !> A set of constants of the size found for Alloy 617 near 950 C, with both recovery
   !> exponents exercised (m = 2 and 3)
   pure function test_chaboche_model() result(m)
      type(chaboche_model) :: m
      m%youngs = 144000.0_dp
      m%poisson = 0.3_dp
      m%c%s0 = 10.0_dp
      m%c%eta = 500.0_dp
      m%c%n = 5.0_dp
      m%c%q = 30.0_dp
      m%c%b = 20.0_dp
      m%c%c = [8.0e4_dp, 5.0e3_dp]
      m%c%g = [1500.0_dp, 60.0_dp]
      m%c%a = [1.0e-7_dp, 1.0e-6_dp]
      m%c%m = [2.0_dp, 3.0_dp]
   end function test_chaboche_model

   subroutine test_constants(error)
      type(error_type), allocatable, intent(out) :: error
      type(chaboche_model) :: m
      integer :: i
      m = test_chaboche_model()
      do i = 1, chaboche_n_constants
         call chaboche_set_constant(m%c, i, real(i, dp)*1.5_dp)
      end do
      do i = 1, chaboche_n_constants
         call check(error, chaboche_get_constant(m%c, i) == real(i, dp)*1.5_dp, &
                    'get/set of '//trim(chaboche_constant_names(i)))
         if (allocated(error)) return
         call check(error, chaboche_constant_index(' '//chaboche_constant_names(i)) == i, &
                    'index of '//trim(chaboche_constant_names(i)))
         if (allocated(error)) return
         call check(error, chaboche_literature_low(i) <= chaboche_literature_high(i), 'box')
         if (allocated(error)) return
      end do
      call check(error, m%c%c(2) == 12.0_dp .and. m%c%m(2) == 19.5_dp .and. &
                 chaboche_constant_index('ETA') == 2 .and. chaboche_constant_index('x') == 0, &
                 'C2 is constant 8, m2 constant 13; names are case-insensitive')
   end subroutine test_constants

   subroutine test_setup_errors(error)
      type(error_type), allocatable, intent(out) :: error
      type(chaboche_model) :: m
      type(uerror), allocatable :: uerr
      m = test_chaboche_model()
      call chaboche_setup(m, uerr)
      call check(error, .not. allocated(uerr), 'the test constants are admissible')
      if (allocated(error)) return
      m%c%eta = 0.0_dp
      call chaboche_setup(m, uerr)
      call check(error, allocated(uerr), 'eta = 0 rejected')
      if (allocated(error)) return
      call check(error, index(uerr%message, 'eta') > 0, uerr%message)
      if (allocated(error)) return
      m = test_chaboche_model()
      m%c%m(1) = 0.5_dp
      call chaboche_setup(m, uerr)
      call check(error, allocated(uerr), 'm1 < 1 rejected')
      if (allocated(error)) return
      m = test_chaboche_model()
      m%c%g(2) = -1.0_dp
      call chaboche_setup(m, uerr)
      call check(error, allocated(uerr), 'g2 < 0 rejected')
      if (allocated(error)) return
      m = test_chaboche_model()
      m%poisson = 0.5_dp
      call chaboche_setup(m, uerr)
      call check(error, allocated(uerr), 'Poisson 0.5 rejected')
   end subroutine test_setup_errors

   !> The checks every model passes (test_models), here with both recovery exponents active
   subroutine test_jacobian(error)
      type(error_type), allocatable, intent(out) :: error
      call model_rates_jacobian(test_chaboche_model(), error)
   end subroutine test_jacobian

   subroutine test_tangent(error)
      type(error_type), allocatable, intent(out) :: error
      call model_tangent(test_chaboche_model(), error)
   end subroutine test_tangent

   !> Rates of the uniaxial form under strain control (sigma = E (eps - eps_in))
   pure subroutine strain_rates(m, eps, y, ydot)
      type(chaboche_model), intent(in) :: m
      real(dp), intent(in) :: eps, y(nu)
      real(dp), intent(out) :: ydot(nu)
      call chaboche_uniaxial_rates(m, m%youngs*(eps - y(1)), -m%youngs, y, ydot)
   end subroutine strain_rates

   !> Total strain of a triangular cycle of amplitude ea at strain rate rate, time t (s)
   pure real(dp) function triangle(t, ea, rate) result(e)
      real(dp), intent(in) :: t, ea, rate
      real(dp) :: period, tau
      period = 4.0_dp*ea/rate
      tau = modulo(t, period)*rate
      if (tau <= ea) then
         e = tau
      else if (tau <= 3.0_dp*ea) then
         e = 2.0_dp*ea - tau
      else
         e = tau - 4.0_dp*ea
      end if
   end function triangle

   !> Stress of the uniaxial form under the triangular strain history, classical RK4 with
   !> nstep equal steps per quarter cycle (the corners fall on steps), sampled at tout
   pure subroutine chaboche_uniaxial_rk4(m, ea, rate, ncycles, nstep, tout, sig)
      type(chaboche_model), intent(in) :: m
      real(dp), intent(in) :: ea, rate, tout(:)
      integer, intent(in) :: ncycles, nstep
      real(dp), intent(out) :: sig(size(tout))
      real(dp) :: y(nu), k1(nu), k2(nu), k3(nu), k4(nu), h, t, tq
      integer :: i, j
      y = 0.0_dp
      tq = ea/rate
      h = tq/nstep
      t = 0.0_dp
      j = 1
      do i = 1, 4*ncycles*nstep
         call strain_rates(m, triangle(t, ea, rate), y, k1)
         call strain_rates(m, triangle(t + h/2, ea, rate), y + h/2*k1, k2)
         call strain_rates(m, triangle(t + h/2, ea, rate), y + h/2*k2, k3)
         call strain_rates(m, triangle(t + h, ea, rate), y + h*k3, k4)
         y = y + h/6*(k1 + 2*k2 + 2*k3 + k4)
         t = i*h
         do while (j <= size(tout))
            if (abs(tout(j) - t) > 1.0e-9_dp*h) exit
            sig(j) = m%youngs*(triangle(t, ea, rate) - y(1))
            j = j + 1
         end do
      end do
   end subroutine chaboche_uniaxial_rk4

   !> Stress of the 3-D update under uniaxial stress (lateral strains solved by Newton with
   !> the consistent tangent) for the same history, increments of tq/ninc, sampled at tout
   pure subroutine chaboche_uniaxial_update(m, ea, rate, ncycles, ninc, nsubsteps, tout, sig, ok)
      type(chaboche_model), intent(in) :: m
      real(dp), intent(in) :: ea, rate, tout(:)
      integer, intent(in) :: ncycles, ninc, nsubsteps
      real(dp), intent(out) :: sig(size(tout))
      logical, intent(out) :: ok
      real(dp) :: y(ns), ynew(ns), eps(6), deps(6), s(6), c(6, 6), dt, t, tq, lat
      integer :: i, j, it, st, nsub
      y = 0.0_dp
      eps = 0.0_dp
      lat = 0.0_dp
      tq = ea/rate
      dt = tq/ninc
      ok = .false.
      j = 1
      do i = 1, 4*ncycles*ninc
         t = i*dt
         deps = 0.0_dp
         deps(1) = triangle(t, ea, rate) - eps(1)
         ! Lateral strain increment: start from the last one scaled, then Newton on s22 = 0
         deps(2:3) = -m%poisson*deps(1)
         do it = 1, 20
            call m%stress_update(eps, deps, dt, y, s, ynew, c, st, nsub, nsubsteps)
            if (st /= update_status_ok) return
            if (abs(s(2)) <= 1.0e-10_dp*max(abs(s(1)), 1.0_dp)) exit
            deps(2:3) = deps(2:3) - s(2)/(c(2, 2) + c(2, 3))
         end do
         eps = eps + deps
         y = ynew
         do while (j <= size(tout))
            if (abs(tout(j) - t) > 1.0e-9_dp*dt) exit
            sig(j) = s(1)
            j = j + 1
         end do
      end do
      ok = .true.
   end subroutine chaboche_uniaxial_update

   !> Output times: every quarter-cycle / 20 over ncycles
   pure function sample_times(ea, rate, ncycles) result(t)
      real(dp), intent(in) :: ea, rate
      integer, intent(in) :: ncycles
      real(dp), allocatable :: t(:)
      integer :: i
      t = [(i*(ea/rate)/20, i=1, 80*ncycles)]
   end function sample_times

   !> Backward Euler with fine increments converges to the RK4 solution of the uniaxial
   !> form: the 3-D update reduces to the uniaxial equations
   subroutine test_update_vs_rates(error)
      type(error_type), allocatable, intent(out) :: error
      type(chaboche_model) :: m
      real(dp), allocatable :: tout(:), sr(:), su(:)
      real(dp) :: dev
      logical :: ok
      character(len=120) :: buf
      m = test_chaboche_model()
      tout = sample_times(0.005_dp, 1.0e-3_dp, 2)
      allocate (sr(size(tout)), su(size(tout)))
      call chaboche_uniaxial_rk4(m, 0.005_dp, 1.0e-3_dp, 2, 4000, tout, sr)
      call chaboche_uniaxial_update(m, 0.005_dp, 1.0e-3_dp, 2, 200, 16, tout, su, ok)
      if (.not. ok) then
         call test_failed(error, '3-D update under uniaxial stress did not converge')
         return
      end if
      dev = maxval(abs(su - sr))/maxval(abs(sr))
      write (buf, '(a,es10.3,a,f7.2,a)') 'max |update - rates| / peak = ', dev, ' (peak ', &
         maxval(abs(sr)), ' MPa)'
      call check(error, dev <= 1.0e-3_dp .and. maxval(abs(sr)) > 100.0_dp, trim(buf))
   end subroutine test_update_vs_rates

   !> The tight reference (RK4 at two step sizes agreeing to 1e-9 of peak), first-order
   !> convergence of the backward Euler update under uniaxial stress, and 1e-4 of peak after
   !> one Richardson extrapolation
   subroutine test_accuracy(error)
      type(error_type), allocatable, intent(out) :: error
      type(chaboche_model) :: m
      real(dp), allocatable :: tout(:), sr(:), sr2(:), su(:), sx(:)
      real(dp) :: peak, ref_err, err(3), xerr
      integer :: k
      logical :: ok
      character(len=160) :: buf
      m = test_chaboche_model()
      tout = sample_times(0.004_dp, 1.0e-4_dp, 1)
      allocate (sr(size(tout)), sr2(size(tout)), su(size(tout)))
      call chaboche_uniaxial_rk4(m, 0.004_dp, 1.0e-4_dp, 1, 4000, tout, sr)
      call chaboche_uniaxial_rk4(m, 0.004_dp, 1.0e-4_dp, 1, 8000, tout, sr2)
      peak = maxval(abs(sr2))
      ref_err = maxval(abs(sr - sr2))/peak
      call check(error, ref_err <= 1.0e-9_dp, 'RK4 reference not converged: '//real_str(ref_err))
      if (allocated(error)) return
      do k = 1, 3
         call chaboche_uniaxial_update(m, 0.004_dp, 1.0e-4_dp, 1, 100*2**k, 1, tout, su, ok)
         if (.not. ok) then
            call test_failed(error, 'update did not converge')
            return
         end if
         err(k) = maxval(abs(su - sr2))/peak
         if (k == 2) sx = su
      end do
      ! Richardson: the first-order error halves with the increment, so 2 s(dt/2) - s(dt)
      ! removes it
      call chaboche_uniaxial_update(m, 0.004_dp, 1.0e-4_dp, 1, 800, 1, tout, su, ok)
      xerr = maxval(abs(2*su - sx - sr2))/peak
      write (buf, '(a,3es10.3,a,2f6.2,a,es10.3)') 'errors / peak at 200, 400, 800 increments: ', &
         err, '; ratios ', err(1)/err(2), err(2)/err(3), '; extrapolated ', xerr
      call check(error, all([err(1)/err(2), err(2)/err(3)] > 1.7_dp) .and. &
                 all([err(1)/err(2), err(2)/err(3)] < 2.3_dp) .and. xerr <= 1.0e-4_dp, trim(buf))
   end subroutine test_accuracy

   !> The uniaxial drivers through the model interface (RODAS4 and CVODE at their default
   !> tolerances, the single-element umat path at its default increments) against the RK4
   !> reference on two cycles at 1e-3/s and one at 1e-4/s
   subroutine test_drivers(error)
      type(error_type), allocatable, intent(out) :: error
      type(chaboche_model) :: m
      type(history_type) :: h
      type(solver_options) :: opts
      type(sim_result) :: res
      type(uerror), allocatable :: uerr
      real(dp), allocatable :: tout(:), sr(:)
      real(dp) :: dev(3), ea, rate, tq
      integer :: k, ncyc
      character(len=200) :: buf
      m = test_chaboche_model()
      do k = 1, 2
         ea = 0.005_dp - 0.001_dp*(k - 1)
         rate = 1.0e-3_dp/10**(k - 1)
         ncyc = 3 - k
         tq = ea/rate
         call history_from_points([0.0_dp, tq, 3*tq, 5*tq, 7*tq, 8*tq], &
                                  [0.0_dp, ea, -ea, ea, -ea, 0.0_dp], control_strain, h, uerr)
         tout = sample_times(ea, rate, ncyc)
         allocate (sr(size(tout)))
         call chaboche_uniaxial_rk4(m, ea, rate, ncyc, 4000, tout, sr)
         call simulate_rosenbrock(m, h, tout, opts, res, uerr)
         if (.not. allocated(uerr)) dev(1) = maxval(abs(res%stress - sr))/maxval(abs(sr))
         if (.not. allocated(uerr)) call simulate_cvode(m, h, tout, opts, res, uerr)
         if (.not. allocated(uerr)) dev(2) = maxval(abs(res%stress - sr))/maxval(abs(sr))
         if (.not. allocated(uerr)) call simulate_umat(m, h, tout, opts, res, uerr)
         if (.not. allocated(uerr)) dev(3) = maxval(abs(res%stress - sr))/maxval(abs(sr))
         if (allocated(uerr)) then
            call test_failed(error, uerr%message)
            return
         end if
         write (buf, '(a,es8.1,a,3es10.3)') 'rate ', rate, ': |driver - RK4| / peak, RODAS4, CVODE, umat: ', dev
         call check(error, all(dev(1:2) <= 1.0e-4_dp) .and. dev(3) <= 5.0e-3_dp, trim(buf))
         if (allocated(error)) return
         deallocate (sr)
      end do
   end subroutine test_drivers

   !> With an activation energy the rates and their Jacobian at T are theta(T) times those at
   !> tref, theta = exp(-activation/k (1/T - 1/tref)); at tref they are those of the model
   !> without one, bit for bit
   subroutine test_arrhenius(error)
      type(error_type), allocatable, intent(out) :: error
      type(chaboche_model) :: m0, m
      type(uerror), allocatable :: uerr
      real(dp), parameter :: qa = 60000.0_dp, tref = 1223.15_dp, temp = 1173.15_dp
      real(dp) :: y(nu), f0(nu), f(nu), j0(nu, nu), j(nu, nu), theta
      m0 = test_chaboche_model()
      m0%temperature = tref
      call chaboche_setup(m0, uerr)
      m = m0
      call m%set_option('activation', qa, uerr)
      if (.not. allocated(uerr)) call m%set_option('tref', tref, uerr)
      if (.not. allocated(uerr)) call chaboche_setup(m, uerr)
      if (allocated(uerr)) then
         call test_failed(error, uerr%message)
         return
      end if
      y = [1.0e-3_dp, 60.0_dp, 25.0_dp, 12.0_dp]
      call chaboche_uniaxial_rates(m0, 150.0_dp, -m0%youngs, y, f0, j0)
      call chaboche_uniaxial_rates(m, 150.0_dp, -m%youngs, y, f, j)
      call check(error, all(f == f0) .and. all(j == j0), 'at tref the rates differ from the '// &
                 'model without an activation energy')
      if (allocated(error)) return
      m%temperature = temp
      call chaboche_setup(m, uerr)
      theta = exp(-qa/1.9859_dp*(1.0_dp/temp - 1.0_dp/tref))
      call chaboche_uniaxial_rates(m, 150.0_dp, -m%youngs, y, f, j)
      call check(error, maxval(abs(f - theta*f0)/abs(theta*f0)) <= 1.0e-12_dp .and. &
                 maxval(abs(j - theta*j0))/maxval(abs(theta*j0)) <= 1.0e-12_dp, &
                 'rates at 1173.15 K against theta = '//real_str(theta)//' times those at 1223.15 K: '// &
                 real_str(maxval(abs(f - theta*f0)/abs(theta*f0))))
   end subroutine test_arrhenius

   !> The settings' checks: a negative activation energy, a Miller model given one
   subroutine test_arrhenius_input(error)
      type(error_type), allocatable, intent(out) :: error
      type(chaboche_model) :: m
      type(uerror), allocatable :: uerr
      m = test_chaboche_model()
      call m%set_option('activation', -1.0_dp, uerr)
      call check(error, allocated(uerr), 'a negative activation energy passed')
      if (allocated(error)) return
      m%temperature = 1200.0_dp
      m%activation = 50000.0_dp
      call chaboche_setup(m, uerr)
      call check(error, allocated(uerr), 'an activation energy without tref passed')
      if (allocated(error)) return
      call check(error, index(uerr%message, 'needs tref') > 0, uerr%message)
   end subroutine test_arrhenius_input

   pure function real_str(x) result(s)
      real(dp), intent(in) :: x
      character(len=:), allocatable :: s
      character(len=24) :: buf
      write (buf, '(es12.4)') x
      s = trim(adjustl(buf))
   end function real_str
end module test_chaboche
