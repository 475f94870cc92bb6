!> Tests of the FE user-material layer: 3-D, plane strain / axisymmetric and plane stress
!> elements through the same update, their consistent tangents, energies, rejected
!> properties, cut-backs, calls from several threads, and the single-file sources
module test_upf
   use testdrive, only: error_type, unittest_type, new_unittest, check, test_failed
   use usharp_kinds, only: dp
   use usharp_upf, only: upf_update, upf_result, upf_elastic_tangent, perm_abaqus, perm_ansys, &
                         upf_ok, upf_cut, upf_invalid
   use usharp_model_miller, only: miller_model, n_upf_state => n_state
   use test_util, only: read_text
   implicit none
   private
   public :: collect_upf

   !> The thesis's constants at 866.15 K (ksi, s, K)
   real(dp), parameter :: props(13) = [22.5e3_dp, 0.3_dp, 0.8_dp, 7.42e-5_dp, 1.0e15_dp, 0.0_dp, &
                                       0.1_dp, 1.9859_dp, 280.0_dp, 100.0_dp, 5.8_dp, 91000.0_dp, &
                                       1800.0_dp]
   real(dp), parameter :: temp = 866.15_dp

   !> A material point driven in uniaxial stress along 1 through elements of ntens components
   type :: point
      integer :: ntens = 6
      real(dp) :: stran(6) = 0.0_dp, stress(6) = 0.0_dp, statev(n_upf_state) = 0.0_dp
      real(dp) :: ddsdde(6, 6) = 0.0_dp, sse = 0.0_dp, spd = 0.0_dp, work = 0.0_dp
   end type point

contains

   subroutine collect_upf(testsuite)
      type(unittest_type), allocatable, intent(out) :: testsuite(:)
      testsuite = [ &
         new_unittest('ntens-6-4-3-agree-on-uniaxial-path', test_ntens_agree), &
         new_unittest('tangent-fd-plane-strain-ntens-4', test_tangent_4), &
         new_unittest('tangent-fd-plane-stress-ntens-3', test_tangent_3), &
         new_unittest('energy-elastic-sse-is-s2-over-2e', test_energy_elastic), &
         new_unittest('energy-loop-spd-equals-area', test_energy_loop), &
         new_unittest('invalid-property-named-elastic-tangent', test_invalid), &
         new_unittest('cut-back-leaves-elastic-tangent', test_cutback), &
         new_unittest('adapters-reject-with-elastic-tangent', test_adapter_reject), &
         new_unittest('adapters-plane-elements-agree', test_adapters_plane), &
         new_unittest('openmp-threads-bit-for-bit', test_threads), &
         new_unittest('single-file-sources-compile-as-vendors', test_single_files), &
         new_unittest('property-14-gives-d0', test_d0_property)]
   end subroutine collect_upf

   !> Positions of the lateral normal strains solved for zero lateral stress
   pure function lateral(ntens) result(lat)
      integer, intent(in) :: ntens
      integer, allocatable :: lat(:)
      if (ntens == 3) then
         lat = [2]
      else
         lat = [2, 3]
      end if
   end function lateral

   !> One increment of axial strain de11 in time dt with zero lateral stresses (Newton on the
   !> lateral strains with the tangent); the point advances, work by the trapezoid rule
   subroutine uniaxial_increment(p, de11, dt, ok)
      type(point), intent(inout) :: p
      real(dp), intent(in) :: de11, dt
      logical, intent(out) :: ok
      type(upf_result) :: res
      type(miller_model) :: mm
      real(dp) :: d(6), s(6), v(n_upf_state), c(6, 6), a(2, 2), r(2)
      integer, allocatable :: lat(:)
      integer :: it, n
      n = p%ntens
      lat = lateral(n)
      d = 0.0_dp
      d(1) = de11
      d(lat) = -0.5_dp*de11
      ok = .false.
      do it = 1, 30
         s = p%stress
         v = p%statev
         call upf_update(mm, props, temp, dt, perm_abaqus, n, p%stran(:n), d(:n), s(:n), v, c(:n, :n), res)
         if (res%status /= upf_ok) return
         if (maxval(abs(s(lat))) <= 1.0e-11_dp*max(maxval(abs(s(:n))), 22.5_dp)) exit
         a(:size(lat), :size(lat)) = c(lat, lat)
         r(:size(lat)) = s(lat)
         if (size(lat) == 1) then
            d(2) = d(2) - r(1)/a(1, 1)
         else
            d(2:3) = d(2:3) - [a(2, 2)*r(1) - a(1, 2)*r(2), a(1, 1)*r(2) - a(2, 1)*r(1)]/ &
                     (a(1, 1)*a(2, 2) - a(1, 2)*a(2, 1))
         end if
      end do
      if (it > 30) return
      p%work = p%work + 0.5_dp*dot_product(p%stress(:n) + s(:n), d(:n))
      p%stran(:n) = p%stran(:n) + d(:n)
      p%stress(:n) = s(:n)
      p%statev = v
      p%ddsdde(:n, :n) = c(:n, :n)
      p%sse = res%sse
      p%spd = p%spd + res%dspd
      ok = .true.
   end subroutine uniaxial_increment

   !> Axial strain at time t of a triangle wave of amplitude amp and period per (starts at 0)
   pure real(dp) function triangle(t, amp, per) result(e)
      real(dp), intent(in) :: t, amp, per
      real(dp) :: u
      u = modulo(t/per + 0.25_dp, 1.0_dp)
      e = amp*(1.0_dp - 4.0_dp*abs(u - 0.5_dp))
   end function triangle

   !> Plane stress tangent from a 3-D one (Abaqus order): condense out 33, keep 11 22 12
   pure function condense(c6) result(c3)
      real(dp), intent(in) :: c6(6, 6)
      real(dp) :: c3(3, 3)
      integer, parameter :: k(3) = [1, 2, 4]
      integer :: i, j
      do j = 1, 3
         do i = 1, 3
            c3(i, j) = c6(k(i), k(j)) - c6(k(i), 3)*c6(3, k(j))/c6(3, 3)
         end do
      end do
   end function condense

   !> Largest relative difference, scaled by the largest entry of b
   pure real(dp) function rdiff(a, b)
      real(dp), intent(in) :: a(:), b(:)
      rdiff = maxval(abs(a - b))/max(maxval(abs(b)), tiny(1.0_dp))
   end function rdiff

   !> The same uniaxial LCF path (+-0.6 %, 2e-4 1/s, 0.5 s increments, 1.5 cycles) through
   !> 3-D, plane strain and plane stress points: stresses, states and tangents agree
   subroutine test_ntens_agree(error)
      type(error_type), allocatable, intent(out) :: error
      type(point) :: p6, p4, p3
      real(dp) :: t, dt, e_old, dev(3), worst(3), c3(3, 3)
      integer :: k
      logical :: ok6, ok4, ok3
      character(len=200) :: buf
      p6%ntens = 6
      p4%ntens = 4
      p3%ntens = 3
      dt = 0.5_dp
      worst = 0.0_dp
      e_old = 0.0_dp
      do k = 1, 180
         t = k*dt
         call uniaxial_increment(p6, triangle(t, 0.006_dp, 120.0_dp) - e_old, dt, ok6)
         call uniaxial_increment(p4, triangle(t, 0.006_dp, 120.0_dp) - e_old, dt, ok4)
         call uniaxial_increment(p3, triangle(t, 0.006_dp, 120.0_dp) - e_old, dt, ok3)
         e_old = triangle(t, 0.006_dp, 120.0_dp)
         if (.not. (ok6 .and. ok4 .and. ok3)) then
            write (buf, '(a,i0,3l2)') 'uniaxial increment failed at ', k, ok6, ok4, ok3
            call test_failed(error, trim(buf))
            return
         end if
         c3 = condense(p6%ddsdde)
         dev(1) = max(rdiff(p4%stress(1:1), p6%stress(1:1)), rdiff(p3%stress(1:1), p6%stress(1:1)))
         dev(2) = max(rdiff(p4%statev, p6%statev), rdiff(p3%statev, p6%statev))
         dev(3) = max(rdiff(reshape(p4%ddsdde(1:4, 1:4), [16]), reshape(p6%ddsdde(1:4, 1:4), [16])), &
                      rdiff(reshape(p3%ddsdde(1:3, 1:3), [9]), reshape(c3, [9])))
         worst = max(worst, dev)
      end do
      write (buf, '(a,3es10.2,a,f7.3,a,es10.3)') 'max rel. diff stress, state, tangent', &
         worst, '; s11 end ', p6%stress(1), ' ksi; ein11 ', p6%statev(1)
      call check(error, all(worst <= 1.0e-8_dp) .and. p6%statev(1) < -1.0e-3_dp, trim(buf))
   end subroutine test_ntens_agree

   !> Property 14, D0, stands for state 7's start: an increment from state 7 = 0 with it is
   !> the increment from state 7 = D0 without it, bit for bit; without either D0 is the
   !> formula's (11.06 ksi here), and the stress differs
   subroutine test_d0_property(error)
      type(error_type), allocatable, intent(out) :: error
      type(upf_result) :: res
      type(miller_model) :: mm
      real(dp) :: d(6), s14(6), s13(6), sf(6), v(n_upf_state), c(6, 6)
      d = [2.0e-3_dp, -1.0e-3_dp, -1.0e-3_dp, 0.0_dp, 0.0_dp, 0.0_dp]
      s14 = 0.0_dp
      v = 0.0_dp
      call upf_update(mm, [props, 30.0_dp], temp, 1.0_dp, perm_abaqus, 6, spread(0.0_dp, 1, 6), d, s14, v, c, res)
      call check(error, res%status == upf_ok .and. v(7) > 0.0_dp, 'with property 14')
      if (allocated(error)) return
      s13 = 0.0_dp
      v = 0.0_dp
      v(7) = 30.0_dp
      call upf_update(mm, props, temp, 1.0_dp, perm_abaqus, 6, spread(0.0_dp, 1, 6), d, s13, v, c, res)
      call check(error, res%status == upf_ok .and. all(s13 == s14), 'state 7 = 30 and property 14 = 30 agree')
      if (allocated(error)) return
      sf = 0.0_dp
      v = 0.0_dp
      call upf_update(mm, props, temp, 1.0_dp, perm_abaqus, 6, spread(0.0_dp, 1, 6), d, sf, v, c, res)
      call check(error, res%status == upf_ok .and. abs(sf(1) - s14(1)) > 1.0e-3_dp*abs(s14(1)), &
                 'the formula''s D0 gives another stress')
   end subroutine test_d0_property

   !> Consistent tangent of one inelastic increment against central differences, for the
   !> elements of ntens components (code vectors, engineering shear)
   subroutine tangent_fd(error, ntens)
      type(error_type), allocatable, intent(out) :: error
      integer, intent(in) :: ntens
      type(point) :: p
      type(upf_result) :: res
      type(miller_model) :: mm
      real(dp) :: d(ntens), s(ntens), sp(ntens), sm(ntens), v(n_upf_state), c(ntens, ntens)
      real(dp) :: fd(ntens, ntens), cd(ntens, ntens), h, dev, e_old
      integer :: j, k
      logical :: ok
      character(len=120) :: buf
      ! Load past yield in uniaxial tension, then a multiaxial increment with shear
      p%ntens = ntens
      e_old = 0.0_dp
      do k = 1, 20
         call uniaxial_increment(p, 2.0e-4_dp, 1.0_dp, ok)
      end do
      d = 0.0_dp
      d(1:2) = [2.0e-4_dp, -9.0e-5_dp]
      d(ntens) = 4.0e-5_dp
      if (ntens == 4) d(3) = -5.0e-5_dp
      s = p%stress(:ntens)
      v = p%statev
      call upf_update(mm, props, temp, 0.15_dp, perm_abaqus, ntens, p%stran(:ntens), d, s, v, c, res)
      if (res%status /= upf_ok) then
         call test_failed(error, 'update did not converge')
         return
      end if
      h = 1.0e-7_dp
      do j = 1, ntens
         d(j) = d(j) + h
         sp = p%stress(:ntens)
         v = p%statev
         call upf_update(mm, props, temp, 0.15_dp, perm_abaqus, ntens, p%stran(:ntens), d, sp, v, cd, res)
         d(j) = d(j) - 2*h
         sm = p%stress(:ntens)
         v = p%statev
         call upf_update(mm, props, temp, 0.15_dp, perm_abaqus, ntens, p%stran(:ntens), d, sm, v, cd, res)
         d(j) = d(j) + h
         fd(:, j) = (sp - sm)/(2*h)
      end do
      dev = maxval(abs(c - fd))/maxval(abs(fd))
      call upf_elastic_tangent(props, perm_abaqus, ntens, cd)
      write (buf, '(a,i0,a,es10.3,a,es11.4,a,es11.4)') 'ntens ', ntens, ': max |C - FD| / max |FD| = ', &
         dev, '; C11 ', c(1, 1), ' (elastic ', cd(1, 1)
      call check(error, dev <= 1.0e-6_dp .and. c(1, 1) < 0.9_dp*cd(1, 1), trim(buf)//')')
   end subroutine tangent_fd

   subroutine test_tangent_4(error)
      type(error_type), allocatable, intent(out) :: error
      call tangent_fd(error, 4)
   end subroutine test_tangent_4

   subroutine test_tangent_3(error)
      type(error_type), allocatable, intent(out) :: error
      call tangent_fd(error, 3)
   end subroutine test_tangent_3

   !> Fast uniaxial loading (1e-4 in 1 ms): SSE = s11^2 / (2E), the inelastic work tiny
   subroutine test_energy_elastic(error)
      type(error_type), allocatable, intent(out) :: error
      type(point) :: p
      logical :: ok
      character(len=120) :: buf
      real(dp) :: ref
      call uniaxial_increment(p, 1.0e-4_dp, 1.0e-3_dp, ok)
      ref = p%stress(1)**2/(2*props(1))
      write (buf, '(a,es12.5,a,es12.5,a,es9.2)') 'SSE ', p%sse, ' ksi, s^2/2E ', ref, '; SPD ', p%spd
      call check(error, ok .and. abs(p%sse - ref) <= 1.0e-9_dp*ref .and. p%spd < 1.0e-6_dp*ref &
                 .and. abs(p%stress(1) - 2.25_dp) < 1.0e-3_dp, trim(buf))
   end subroutine test_energy_elastic

   !> Three LCF cycles of +-0.6 %: the energy balance W = SSE + SPD closes to rounding
   !> (both by the trapezoid rule), and over the last cycle, from one compression peak to the
   !> next, SPD equals the area of the hysteresis loop within 1 %
   subroutine test_energy_loop(error)
      type(error_type), allocatable, intent(out) :: error
      type(point) :: p
      real(dp) :: t, e_old, w0, spd0, area, spd_cycle, balance
      integer :: k
      logical :: ok
      character(len=160) :: buf
      e_old = 0.0_dp
      w0 = 0.0_dp
      spd0 = 0.0_dp
      do k = 1, 330
         t = k*1.0_dp
         call uniaxial_increment(p, triangle(t, 0.006_dp, 120.0_dp) - e_old, 1.0_dp, ok)
         if (.not. ok) then
            call test_failed(error, 'uniaxial increment failed')
            return
         end if
         e_old = triangle(t, 0.006_dp, 120.0_dp)
         if (k == 210) then  ! a compression peak (t = 90 + 120 m)
            w0 = p%work
            spd0 = p%spd
         end if
      end do
      area = p%work - w0
      spd_cycle = p%spd - spd0
      balance = abs(p%work - p%sse - p%spd)/p%work
      write (buf, '(a,es9.2,a,f9.5,a,f9.5,a,es9.2)') 'balance |W - SSE - SPD| / W = ', balance, &
         '; last cycle SPD ', spd_cycle, ' ksi, loop area ', area, ' ksi, rel. ', &
         abs(spd_cycle - area)/area
      call check(error, balance <= 1.0e-10_dp .and. abs(spd_cycle - area) <= 0.01_dp*area &
                 .and. area > 0.05_dp, trim(buf))
   end subroutine test_energy_loop

   !> A negative A1 is rejected with a message naming A1; stress and state are unchanged and
   !> the tangent is the elastic one
   subroutine test_invalid(error)
      type(error_type), allocatable, intent(out) :: error
      type(upf_result) :: res
      type(miller_model) :: mm
      real(dp) :: bad(13), s(6), v(13), c(6, 6), ce(6, 6), c4(4, 4), ce4(4, 4)
      bad = props
      bad(3) = -0.8_dp
      s = 1.0_dp
      v = 0.0_dp
      call upf_update(mm, bad, temp, 0.1_dp, perm_ansys, 6, [real(dp) :: 0, 0, 0, 0, 0, 0], &
                      [1.0e-4_dp, 0.0_dp, 0.0_dp, 0.0_dp, 0.0_dp, 0.0_dp], s, v, c, res)
      call upf_elastic_tangent(props, perm_ansys, 6, ce)
      call check(error, res%status == upf_invalid .and. index(res%message, 'A1') > 0 .and. &
                 all(s == 1.0_dp) .and. all(v == 0.0_dp) .and. all(c == ce) .and. &
                 abs(ce(1, 1) - 22.5e3_dp*0.7_dp/(1.3_dp*0.4_dp)) < 1.0e-9_dp, &
                 'A1 < 0: "'//trim(res%message)//'"')
      if (allocated(error)) return
      bad = props
      bad(13) = 800.0_dp   ! Tm below the temperature
      call upf_update(mm, bad, temp, 0.1_dp, perm_abaqus, 4, [real(dp) :: 0, 0, 0, 0], &
                      [1.0e-4_dp, 0.0_dp, 0.0_dp, 0.0_dp], s(1:4), v, c4, res)
      call upf_elastic_tangent(props, perm_abaqus, 4, ce4)
      call check(error, res%status == upf_invalid .and. index(res%message, 'Tm') > 0 .and. &
                 all(c4 == ce4), 'Tm < T: "'//trim(res%message)//'"')
   end subroutine test_invalid

   !> An increment the local Newton cannot solve (a NaN strain increment, as a diverging
   !> global iteration may hand over) asks for a cut-back and leaves stress and state
   !> unchanged and the tangent elastic
   subroutine test_cutback(error)
      use, intrinsic :: ieee_arithmetic, only: ieee_value, ieee_quiet_nan
      type(error_type), allocatable, intent(out) :: error
      type(upf_result) :: res
      type(miller_model) :: mm
      real(dp) :: s(3), v(13), c(3, 3), ce(3, 3)
      s = [3.0_dp, 0.0_dp, 0.0_dp]
      v = 0.0_dp
      call upf_update(mm, props, temp, 0.1_dp, perm_abaqus, 3, [0.0_dp, 0.0_dp, 0.0_dp], &
                      [1.0e-3_dp, ieee_value(1.0_dp, ieee_quiet_nan), 0.0_dp], s, v, c, res)
      call upf_elastic_tangent(props, perm_abaqus, 3, ce)
      call check(error, res%status == upf_cut .and. all(s == [3.0_dp, 0.0_dp, 0.0_dp]) .and. &
                 all(v == 0.0_dp) .and. all(c == ce) .and. abs(ce(1, 1) - 22.5e3_dp/0.91_dp) < 1.0e-9_dp, &
                 'cut-back with an elastic plane-stress tangent: status '//achar(48 + res%status))
   end subroutine test_cutback

   !> The adapters given bad input (a negative n, beam elements) return an elastic
   !> tangent and ask to stop: Abaqus PNEWDT <= 1e-6, ANSYS keycut = 1
   subroutine test_adapter_reject(error)
      use test_update, only: umat, usermat
      type(error_type), allocatable, intent(out) :: error
      real(dp) :: s(4), v(13), c(4, 4), ce(4, 4), z, z2(2), z4(4), zz(4), z4b(4), z4c(4), z3(3)
      real(dp) :: z33(3, 3), pnewdt, sse, spd, scd, rpl, drpldt, bad(13), c3(3, 3), s3(3)
      real(dp) :: o(11), cutf
      integer :: keycut
      character(len=80) :: cm
      o = 0; s = 0; v = 0; z = 0; z2 = 0; z4 = 0; zz = 0; z3 = 0; z33 = 0; z4b = 0; z4c = 0
      sse = 0; spd = 0; scd = 0; rpl = 0; drpldt = 0
      cm = 'BADMAT'
      bad = props
      bad(11) = -5.8_dp
      pnewdt = 1.0_dp
      ! Print the message into the test log as an FE code's log would show it
      call umat(s, v, c, sse, spd, scd, rpl, z4b, z4c, drpldt, zz, [1.0e-4_dp, 0.0_dp, 0.0_dp, 0.0_dp], &
                z2, 0.1_dp, temp, z, z4, z4, cm, 3, 1, 4, 13, bad, 13, z3, z33, pnewdt, z, z33, z33, &
                1, 1, 1, 1, 1, 1)
      call upf_elastic_tangent(props, perm_abaqus, 4, ce)
      call check(error, pnewdt <= 1.0e-6_dp .and. all(c == ce) .and. all(s == 0.0_dp), &
                 'Abaqus UMAT, n < 0: PNEWDT small, DDSDDE elastic')
      if (allocated(error)) return
      pnewdt = 1.0_dp
      c3 = -1.0_dp
      s3 = 0.0_dp
      call umat(s3, v, c3, sse, spd, scd, rpl, z4b(1:3), z4c(1:3), drpldt, zz(1:3), &
                [1.0e-4_dp, 0.0_dp, 0.0_dp], z2, 0.1_dp, temp, z, z4, z4, cm, 1, 2, 3, 13, props, 13, &
                z3, z33, pnewdt, z, z33, z33, 1, 2, 1, 1, 1, 1)
      call check(error, pnewdt <= 1.0e-6_dp .and. all(c3 /= -1.0_dp) .and. all(s3 == 0.0_dp), &
                 'Abaqus UMAT, beam (NDI = 1): PNEWDT small, DDSDDE set')
      if (allocated(error)) return
      ! CalculiX passes PNEWDT = -1 (no request): a cut must still be asked for
      pnewdt = -1.0_dp
      call umat(s, v, c, sse, spd, scd, rpl, z4b, z4c, drpldt, zz, [1.0e-4_dp, 0.0_dp, 0.0_dp, 0.0_dp], &
                z2, 0.1_dp, temp, z, z4, z4, cm, 3, 1, 4, 13, bad, 13, z3, z33, pnewdt, z, z33, z33, &
                1, 1, 1, 1, 1, 1)
      call check(error, pnewdt > 0.0_dp .and. pnewdt <= 1.0e-6_dp, 'Abaqus UMAT, PNEWDT = -1 on entry')
      if (allocated(error)) return
      c = -1.0_dp
      cutf = 1.0_dp
      call usermat(7, 1, 1, 1, 1, 1, 1, keycut, 3, 1, 4, 13, 13, z, 0.1_dp, temp, z, s, v, c, o(1), &
                   o(2), o(3), zz, [1.0e-4_dp, 0.0_dp, 0.0_dp, 0.0_dp], z4, bad, z3, z, z33, z33, z2, &
                   o(4), cutf, o(5), o(6), o(7), o(8), o(9), o(10), o(11))
      call check(error, keycut == 1 .and. all(c == ce) .and. all(s == 0.0_dp), &
                 'ANSYS USERMAT, n < 0: keycut = 1, dsdePl elastic')
   end subroutine test_adapter_reject

   !> Plane strain (4 components) and plane stress (3) increments through the Abaqus UMAT and
   !> the ANSYS USERMAT: stresses, tangents and states equal each other (bit for bit: the
   !> 2-D component orders agree and the states differ by the 13/23 swap) and the core
   !> update's; the energies and the ANSYS extras are filled in
   subroutine test_adapters_plane(error)
      use test_update, only: umat, usermat
      integer, parameter :: swap(13) = [1, 2, 3, 4, 6, 5, 7, 8, 9, 10, 11, 13, 12]
      type(error_type), allocatable, intent(out) :: error
      type(upf_result) :: res
      type(miller_model) :: mm
      real(dp) :: sa(4), sb(4), sc(4), va(13), vb(13), vc(13), ca(4, 4), cb(4, 4), cc(4, 4)
      real(dp) :: e(4), d(4), z, z2(2), z3(3), z33(3, 3), z4(4), zb(4), zc(4), pnewdt, cutf
      real(dp) :: sse, spd, scd, rpl, drpldt, sedel, sedpl, epseq, epspl(4), epszz
      integer :: nt, k, keycut, ndi
      logical :: ok
      character(len=80) :: cm
      character(len=120) :: buf
      cm = 'MILLER'
      z = 0; z2 = 0; z3 = 0; z33 = 0; z4 = 0; zb = 0; zc = 0
      do nt = 4, 3, -1
         ndi = merge(3, 2, nt == 4)
         sa = 0; sb = 0; sc = 0; va = 0; vb = 0; vc = 0; e = 0
         sse = 0; spd = 0; scd = 0; rpl = 0; drpldt = 0; sedel = 0; sedpl = 0; epseq = 0
         epspl = 0; epszz = 0
         d = 0
         d(1:2) = [3.0e-4_dp, -1.0e-4_dp]
         d(nt) = 1.0e-4_dp
         do k = 1, 30
            pnewdt = 1.0e36_dp
            cutf = 1.0_dp
            call umat(sa(:nt), va, ca(:nt, :nt), sse, spd, scd, rpl, zb(:nt), zc(:nt), drpldt, e(:nt), &
                      d(:nt), z2, 0.5_dp, temp, z, z4, z4, cm, ndi, 1, nt, 13, props, 13, z3, z33, &
                      pnewdt, z, z33, z33, 1, 1, 1, 1, 1, k)
            call usermat(1, 1, 1, 1, 1, 1, 1, keycut, ndi, 1, nt, 13, 13, z, 0.5_dp, temp, z, &
                         sb(:nt), vb, cb(:nt, :nt), sedel, sedpl, epseq, e(:nt), d(:nt), epspl(:nt), &
                         props, z3, z, z33, z33, z2, epszz, cutf, z, z, z, z, z, z, z)
            call upf_update(mm, props, temp, 0.5_dp, perm_abaqus, nt, e(:nt), d(:nt), sc(:nt), vc, &
                            cc(:nt, :nt), res)
            if (pnewdt < 1.0_dp .or. keycut /= 0 .or. res%status /= upf_ok) then
               call test_failed(error, 'an increment was cut')
               return
            end if
            e = e + d
            if (any(sa(:nt) /= sb(:nt)) .or. any(sa(:nt) /= sc(:nt)) .or. &
                any(ca(:nt, :nt) /= cb(:nt, :nt)) .or. any(ca(:nt, :nt) /= cc(:nt, :nt)) .or. &
                any(va /= vc) .or. any(va /= vb(swap)) .or. sse /= sedel .or. spd /= sedpl) then
               write (buf, '(a,i0,a,i0)') 'adapters differ for ntens ', nt, ' at increment ', k
               call test_failed(error, trim(buf))
               return
            end if
         end do
         write (buf, '(a,i0,a,2es11.3,a,es11.3)') 'ntens ', nt, ': SPD, epseq ', spd, epseq, &
            ', epsZZ ', epszz
         if (nt == 3) then
            ok = epszz < -1.0e-3_dp .and. all(epspl(1:3) == vb([1, 2, 4]))
         else
            ok = all(epspl == vb(1:4))
         end if
         call check(error, ok .and. spd > 0.0_dp .and. epseq > 1.0e-3_dp .and. sse > 0.0_dp, trim(buf))
         if (allocated(error)) return
      end do
   end subroutine test_adapters_plane

   !> Eight material points with different histories (3-D, plane strain and plane stress),
   !> updated from four OpenMP threads, give the serial results bit for bit
   subroutine test_threads(error)
      type(error_type), allocatable, intent(out) :: error
      integer, parameter :: npts = 8, ninc = 40
      integer, parameter :: kinds(npts) = [6, 4, 3, 6, 4, 3, 6, 6]
      type(point) :: ser(npts), par(npts)
      logical :: oks(npts), okp(npts)
      integer :: i, k, ndiff
      character(len=100) :: buf
      do i = 1, npts
         ser(i)%ntens = kinds(i)
      end do
      par = ser
      oks = .true.
      okp = .true.
      do i = 1, npts
         do k = 1, ninc
            call advance(ser(i), i, k, oks(i))
         end do
      end do
      !$omp parallel do num_threads(4) schedule(static, 1) private(k)
      do i = 1, npts
         do k = 1, ninc
            call advance(par(i), i, k, okp(i))
         end do
      end do
      !$omp end parallel do
      ndiff = 0
      do i = 1, npts
         if (any(ser(i)%stress /= par(i)%stress) .or. any(ser(i)%statev /= par(i)%statev) .or. &
             any(ser(i)%ddsdde /= par(i)%ddsdde) .or. ser(i)%spd /= par(i)%spd) ndiff = ndiff + 1
      end do
      write (buf, '(a,i0,a,i0,a,l1)') 'points differing: ', ndiff, ' of ', npts, '; all converged ', &
         all(oks .and. okp)
      call check(error, ndiff == 0 .and. all(oks .and. okp) .and. &
                 all([(ser(i)%statev(1) /= ser(1)%statev(1), i = 2, npts)]), trim(buf))
   contains
      !> Point i: strain rate growing with i, alternating in sign every 20 increments
      subroutine advance(p, i, k, ok)
         type(point), intent(inout) :: p
         integer, intent(in) :: i, k
         logical, intent(inout) :: ok
         logical :: okk
         call uniaxial_increment(p, merge(1.0_dp, -1.0_dp, mod((k - 1)/20, 2) == 0)*1.0e-4_dp* &
                                 (1.0_dp + 0.25_dp*i), 0.5_dp, okk)
         ok = ok .and. okk
      end subroutine advance
   end subroutine test_threads

   !> scripts/build-umat.sh writes the single-file Abaqus/CalculiX and ANSYS sources and
   !> compiles each as the vendor's build treats it (fixed form), warnings as errors
   subroutine test_single_files(error)
      type(error_type), allocatable, intent(out) :: error
      integer :: stat
      call execute_command_line('bash scripts/build-umat.sh --check build/test-scratch/umat-single '// &
                                '> build/test-scratch-umat-single.log 2>&1', exitstat=stat)
      call check(error, stat, 0, 'scripts/build-umat.sh --check (see build/test-scratch-umat-single.log)')
      if (allocated(error)) return
      call abaqus_point_report(error)
   end subroutine test_single_files

   !> The Abaqus single file, called at integration point 2 above the melting temperature
   !> (1900 K against Tm 1800 K): that point reports the problem in the message file and ends
   !> the analysis by XIT (a driver stands in for Abaqus: XIT writes a line and stops)
   subroutine abaqus_point_report(error)
      type(error_type), allocatable, intent(out) :: error
      character(len=*), parameter :: d = 'build/test-scratch/umat-single/check-umat_miller_abaqus'
      character(len=:), allocatable :: msg, out
      integer :: stat, cstat
      call execute_command_line('cd '//d//' && printf ''%s\n'' '// &
         '"program drv" "  implicit none" "  integer, parameter :: dp = kind(1d0)" '// &
         '"  real(dp) :: s(6), v(13), c(6,6), sse, spd, scd, rpl, ddt(6), dde(6), dpt, e(6), de(6)" '// &
         '"  real(dp) :: t(2), p(13), x(3), r(3,3), pnewdt, f0(3,3), f1(3,3), pr(1), dpr(1)" '// &
         '"  character(len=80) :: cm = ''MILLER''" '// &
         '"  p = [22500d0,0.3d0,0.8d0,7.42d-5,1d15,0d0,0.1d0,1.9859d0,280d0,100d0,5.8d0,91000d0,1800d0]" '// &
         '"  s = 0; v = 0; e = 0; de = 0; de(1) = 1d-3; t = 0; pnewdt = 1d36; x = 0; r = 0; f0 = 0; f1 = 0" '// &
         '"  open (7, file=''msg.txt'')" '// &
         '"  call umat(s, v, c, sse, spd, scd, rpl, ddt, dde, dpt, e, de, t, 1d0, 1900d0, 0d0, pr, dpr, &" '// &
         '"    cm, 3, 3, 6, 13, p, 13, x, r, pnewdt, 1d0, f0, f1, 1, 2, 0, 0, 1, 1)" '// &
         '"  print *, ''no XIT''" "end program drv" "subroutine xit()" "  print *, ''XIT called''" '// &
         '"  close (7)" "  stop" "end subroutine xit" > drv.f90 && gfortran drv.f90 umat_miller_abaqus.o '// &
         '-o drv > drv.log 2>&1 && ./drv > drv.out 2>&1', exitstat=stat, cmdstat=cstat)
      call check(error, stat == 0 .and. cstat == 0, 'driver of the Abaqus single file built and ran (see '// &
                 d//'/drv.log)')
      if (allocated(error)) return
      msg = read_text(d//'/msg.txt')
      out = read_text(d//'/drv.out')
      call check(error, index(out, 'XIT called') > 0 .and. index(msg, '***ERROR: usharp Miller material '// &
                 'MILLER: ') > 0, 'point 2 above Tm: message and XIT; printed: '//out//' message file: '//msg)
   end subroutine abaqus_point_report
end module test_upf
