!> Tests of the implicit stress update and the single-element (umat) driver
module test_update
   use testdrive, only: error_type, unittest_type, new_unittest, check, test_failed
   use usharp_kinds, only: dp
   use usharp_error, only: uerror => error_type
   use usharp_model_miller, only: miller_model, model_setup
   use usharp_model_miller, only: n_state
   use usharp_model, only: update_status_ok
   use usharp_history, only: history_type, output_times, history_from_points, control_strain
   use usharp_simulation, only: solver_options, sim_result
   use usharp_cvode_driver, only: simulate_cvode
   use usharp_umat_driver, only: simulate_umat
   use test_driver, only: thesis_test
   implicit none
   private
   public :: collect_update
   !> The adapters' interfaces, for the other suites that call them
   public :: umat, usermat

   real(dp), parameter :: s2 = sqrt(2.0_dp)

   interface
      subroutine usermat(matId, elemId, kDomIntPt, kLayer, kSectPt, ldstep, isubst, keycut, &
                         nDirect, nShear, ncomp, nStatev, nProp, Time, dTime, Temp, dTemp, &
                         stress, ustatev, dsdePl, sedEl, sedPl, epseq, Strain, dStrain, epsPl, &
                         prop, coords, var0, defGrad_t, defGrad, tsstif, epsZZ, cutFactor, &
                         var1, var2, var3, var4, var5, var6, var7)
         import :: dp
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
      end subroutine usermat
      subroutine umat(stress, statev, ddsdde, sse, spd, scd, rpl, ddsddt, drplde, drpldt, stran, &
                      dstran, time, dtime, temp, dtemp, predef, dpred, cmname, ndi, nshr, ntens, &
                      nstatv, props, nprops, coords, drot, pnewdt, celent, dfgrd0, dfgrd1, noel, npt, &
                      layer, kspt, kstep, kinc)
         import :: dp
         integer, intent(in) :: ndi, nshr, ntens, nstatv, nprops, noel, npt, layer, kspt, kstep, kinc
         character(len=80), intent(in) :: cmname
         real(dp), intent(inout) :: stress(ntens), statev(nstatv), ddsdde(ntens, ntens)
         real(dp), intent(inout) :: sse, spd, scd, rpl, ddsddt(ntens), drplde(ntens), drpldt
         real(dp), intent(in) :: stran(ntens), dstran(ntens), time(2), dtime, temp, dtemp
         real(dp), intent(in) :: predef(*), dpred(*), props(nprops), coords(3), drot(3, 3)
         real(dp), intent(inout) :: pnewdt
         real(dp), intent(in) :: celent, dfgrd0(3, 3), dfgrd1(3, 3)
      end subroutine umat
   end interface

contains

   subroutine collect_update(testsuite)
      type(unittest_type), allocatable, intent(out) :: testsuite(:)
      testsuite = [ &
         new_unittest('tangent-fd-elastic', test_tangent_elastic), &
         new_unittest('tangent-fd-strongly-inelastic', test_tangent_inelastic), &
         new_unittest('umat-matches-cvode-thesis-tests', test_umat_vs_cvode), &
         new_unittest('umat-first-order-convergence', test_order), &
         new_unittest('ansys-and-abaqus-adapters-agree', test_adapters), &
         new_unittest('drop-in-source-builds-warnings-as-errors', test_dropin_build), &
         new_unittest('calculix-c3d8-cube-matches-uniaxial-driver', test_calculix)]
   end subroutine collect_update

   !> Largest relative difference between the tangent and central differences of the update
   subroutine tangent_check(error, m, eps0, deps, dt, y0)
      type(error_type), allocatable, intent(out) :: error
      type(miller_model), intent(in) :: m
      real(dp), intent(in) :: eps0(6), deps(6), dt, y0(n_state)
      real(dp) :: sig(6), y(n_state), c(6, 6), fd(6, 6), sp(6), sm(6), cdum(6, 6), d(6), hstep, dev
      integer :: j, st, nsub
      character(len=100) :: buf
      call m%stress_update(eps0, deps, dt, y0, sig, y, c, st, nsub)
      if (st /= update_status_ok) then
         call test_failed(error, 'update did not converge')
         return
      end if
      hstep = 1.0e-7_dp
      do j = 1, 6
         d = 0.0_dp
         d(j) = hstep
         call m%stress_update(eps0, deps + d, dt, y0, sp, y, cdum, st, nsub)
         call m%stress_update(eps0, deps - d, dt, y0, sm, y, cdum, st, nsub)
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

   !> The umat path against CVODE on the thesis's three tests and on a strain history that
   !> starts at 1e-4 (a measured one's start), from which both start elastically
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
      do k = 1, 4
         if (k <= 3) then
            call thesis_test(k, h)
         else
            ! A strain history starting at 1e-4 (a measured one's start)
            call history_from_points([0.0_dp, 10.0_dp, 20.0_dp], [1.0e-4_dp, 3.0e-3_dp, 1.0e-4_dp], &
                                     control_strain, h, uerr)
         end if
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
         ! the umat path starts elastically there, as CVODE does (its first stress had been 0)
         call check(error, abs(ru%stress(1) - rc%stress(1)) <= 1.0e-6_dp*max(abs(rc%stress(1)), 1.0_dp), &
                    'test '//achar(48 + k)//': first stress of umat and cvode')
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
   !> The same physical increments through both adapters: ANSYS orders 11 22 33 12 23 13,
   !> Abaqus 11 22 33 12 13 23; after swapping components 5 and 6 the stresses, states and
   !> tangents must be identical, and equal to the core update's
   subroutine test_adapters(error)
      type(error_type), allocatable, intent(out) :: error
      real(dp), parameter :: props(13) = [22.5e3_dp, 0.3_dp, 0.8_dp, 7.42e-5_dp, 1.0e15_dp, 0.0_dp, &
                                          0.1_dp, 1.9859_dp, 280.0_dp, 100.0_dp, 5.8_dp, 91000.0_dp, 1800.0_dp]
      integer, parameter :: swap(6) = [1, 2, 3, 4, 6, 5]
      real(dp) :: s_an(6), v_an(13), c_an(6, 6), e_an(6), d_an(6)
      real(dp) :: s_ab(6), v_ab(13), c_ab(6, 6), e_ab(6), d_ab(6)
      real(dp) :: z, z3(3), z33(3, 3), z2(2), zz(6), cutf, pnewdt, rate(6)
      real(dp) :: o1, o2, o3, o4, o5, o6, o7, o8, o9, o10, o11, o12, o13, oo(6), oo2(6), oz2(2)
      integer :: keycut, k
      character(len=80) :: cm
      s_an = 0; v_an = 0; e_an = 0; s_ab = 0; v_ab = 0; e_ab = 0
      z = 0; z3 = 0; z33 = 0; z2 = 0; zz = 0; cm = 'MILLER'
      ! ANSYS-order strain rate: tension with shear in 12 and 13, 2e-4/s; 0.15 s increments
      rate = [2.0e-4_dp, -0.6e-4_dp, -0.6e-4_dp, 0.5e-4_dp, 0.0_dp, 0.3e-4_dp]
      do k = 1, 150
         d_an = rate*0.15_dp
         d_ab = d_an(swap)
         cutf = 1; pnewdt = 1
         ! Separate actual arguments for everything an adapter may write (no aliasing)
         o1 = 0; o2 = 0; o3 = 0; o4 = 0; o5 = 0; o6 = 0; o7 = 0; o8 = 0; o9 = 0; o10 = 0
         o11 = 0; o12 = 0; o13 = 0; oo = 0; oo2 = 0; oz2 = 0
         call usermat(1, 1, 1, 1, 1, 1, 1, keycut, 3, 3, 6, 13, 13, z, 0.15_dp, 866.15_dp, z, &
                      s_an, v_an, c_an, o1, o2, o3, e_an, d_an, oo, props, z3, z, z33, z33, oz2, o4, &
                      cutf, o5, o6, o7, o8, o9, o10, o11)
         call umat(s_ab, v_ab, c_ab, o1, o2, o3, o12, oo, oo2, o13, e_ab, d_ab, [z, z], 0.15_dp, &
                   866.15_dp, z, zz, zz, cm, 3, 3, 6, 13, props, 13, z3, z33, pnewdt, z, z33, z33, &
                   1, 1, 1, 1, 1, k)
         if (keycut /= 0 .or. pnewdt < 1) then
            call test_failed(error, 'an adapter asked for a cut-back')
            return
         end if
         e_an = e_an + d_an
         e_ab = e_ab + d_ab
         ! Both adapters hand the same Mandel vectors to the same update: bit for bit equal
         if (any(s_an(swap) /= s_ab) .or. any(c_an(swap, swap) /= c_ab) .or. &
             any(v_an([1, 2, 3, 4, 6, 5, 7, 8, 9, 10, 11, 13, 12]) /= v_ab)) then
            write (cm, '(i4,3es12.3)') k, maxval(abs(s_an(swap) - s_ab)), maxval(abs(c_an(swap, swap) - c_ab)), &
               maxval(abs(v_an([1, 2, 3, 4, 6, 5, 7, 8, 9, 10, 11, 13, 12]) - v_ab))
            call test_failed(error, 'adapters differ after the component swap at increment, stress, '// &
                             'tangent, state: '//trim(cm))
            return
         end if
      end do
      ! The response went well past yield (von Mises of 20 ksi and more)
      call check(error, s_an(1) > 15.0_dp .and. v_an(1) > 1.0e-3_dp, 'inelastic at the end')
   end subroutine test_adapters

   subroutine test_dropin_build(error)
      type(error_type), allocatable, intent(out) :: error
      integer :: stat
      call execute_command_line('bash scripts/build-umat.sh build/test-scratch/umat > /dev/null 2>&1', &
                                exitstat=stat)
      call check(error, stat, 0, 'scripts/build-umat.sh (gfortran -Wall -Wextra -Werror)')
   end subroutine test_dropin_build
   !> The UMAT inside CalculiX (scripts/calculix-check.sh): exit 0 passed, 77 skipped with the
   !> reason it printed, anything else failed
   subroutine test_calculix(error)
      use testdrive, only: skip_test
      use test_util, only: read_text
      type(error_type), allocatable, intent(out) :: error
      integer :: stat
      character(len=:), allocatable :: log
      call execute_command_line('bash scripts/calculix-check.sh > build/calculix-check.log 2>&1', &
                                exitstat=stat)
      log = read_text('build/calculix-check.log')
      if (stat == 77) then
         call skip_test(error, last_line(log))
      else
         call check(error, stat, 0, 'scripts/calculix-check.sh: '//last_line(log))
      end if
   contains
      function last_line(text) result(line)
         character(len=*), intent(in) :: text
         character(len=:), allocatable :: line
         integer :: k
         line = text
         if (len(line) > 0) line = line(:len(line) - 1)
         k = index(line, new_line('a'), back=.true.)
         line = line(k + 1:)
      end function last_line
   end subroutine test_calculix
end module test_update
