!> usharp's own elementary functions against the same functions in quadruple precision (a
!> reference some 2**60 times tighter), in units in the last place of the double result
module test_math
   use testdrive, only: error_type, unittest_type, new_unittest, check, test_failed
   use usharp_kinds, only: dp
   use usharp_rng, only: rng_type
   use usharp_strings, only: str, lower, real_str
   use usharp_filesys, only: join_path
   use usharp_math, only: exp_dp, expm1_dp, log_dp, log1p_dp, log10_dp, pow_dp, pow10_dp, &
                          asinh_dp, sinh_power_dp, sincos_turn, log_gamma_dp, &
                          spline_power_form, power_piece
   use, intrinsic :: ieee_arithmetic, only: ieee_is_nan, ieee_is_finite
   implicit none
   private
   public :: collect_math

   integer, parameter :: qp = selected_real_kind(30)
   integer, parameter :: nsample = 200000

contains

   subroutine collect_math(testsuite)
      type(unittest_type), allocatable, intent(out) :: testsuite(:)
      testsuite = [ &
         new_unittest('exp-and-log-within-an-ulp', test_exp_log), &
         new_unittest('functions-made-from-exp-and-log', test_derived), &
         new_unittest('sin-and-cos-of-a-turn', test_sincos), &
         new_unittest('log-gamma', test_log_gamma), &
         new_unittest('spline-pieces-in-power-form', test_power_form), &
         new_unittest('special-values', test_special), &
         new_unittest('no-intrinsic-transcendentals-in-src', test_no_intrinsics), &
         new_unittest('text-of-numbers-on-threads-side-by-side', test_text_threads)]
   end subroutine collect_math

   !> Error of y against the reference in units of the last place of the reference
   elemental real(dp) function ulps(y, ref) result(u)
      real(dp), intent(in) :: y
      real(qp), intent(in) :: ref
      u = real(abs(real(y, qp) - ref)/real(spacing(real(ref, dp)), qp), dp)
   end function ulps

   !> A number spread evenly in [a, b]
   real(dp) function draw(rng, a, b)
      type(rng_type), intent(inout) :: rng
      real(dp), intent(in) :: a, b
      draw = a + (b - a)*rng%uniform()
   end function draw

   !> Fail when the largest error (ulp) passes its bound, naming where
   subroutine bound(error, what, worst, at, most)
      type(error_type), allocatable, intent(inout) :: error
      character(len=*), intent(in) :: what
      real(dp), intent(in) :: worst, at, most
      character(len=120) :: line
      write (line, '(a,": ",f0.3," ulp at x = ",es23.16)') what, worst, at
      write (*, '(4x,a)') trim(line)
      if (allocated(error)) return
      if (worst > most) call test_failed(error, trim(line)//' (bound '//trim(adjustl(num(most)))//')')
   contains
      function num(x) result(s)
         real(dp), intent(in) :: x
         character(len=20) :: s
         write (s, '(f0.2)') x
      end function num
   end subroutine bound

   subroutine test_exp_log(error)
      type(error_type), allocatable, intent(out) :: error
      type(rng_type) :: rng
      real(dp) :: x, w(4), at(4), u
      integer :: i
      call rng%seed(11)
      w = 0.0_dp
      at = 0.0_dp
      do i = 1, nsample
         ! exp over its whole range, and near 0 where the table index changes
         x = draw(rng, -745.0_dp, 709.7_dp)
         if (mod(i, 2) == 0) x = draw(rng, -0.1_dp, 0.1_dp)
         u = ulps(exp_dp(x), exp(real(x, qp)))
         if (u > w(1)) then; w(1) = u; at(1) = x; end if
         ! expm1 where it differs from exp - 1
         x = draw(rng, -40.0_dp, 40.0_dp)
         if (mod(i, 2) == 0) x = draw(rng, -1.0_dp, 1.0_dp)*10.0_dp**draw(rng, -12.0_dp, 0.0_dp)
         u = ulps(expm1_dp(x), exp(real(x, qp)) - 1.0_qp)
         if (u > w(2)) then; w(2) = u; at(2) = x; end if
         ! log over every binade, subnormals included, and about 1
         x = 10.0_dp**draw(rng, -320.0_dp, 308.0_dp)
         if (mod(i, 2) == 0) x = draw(rng, 0.5_dp, 2.0_dp)
         u = ulps(log_dp(x), log(real(x, qp)))
         if (u > w(3)) then; w(3) = u; at(3) = x; end if
         x = draw(rng, -1.0_dp, 1.0_dp)*10.0_dp**draw(rng, -12.0_dp, 0.0_dp)
         if (mod(i, 2) == 0) x = 10.0_dp**draw(rng, 0.0_dp, 20.0_dp)
         u = ulps(log1p_dp(x), log(1.0_qp + real(x, qp)))
         if (u > w(4)) then; w(4) = u; at(4) = x; end if
      end do
      call bound(error, 'exp', w(1), at(1), 1.0_dp)
      call bound(error, 'expm1', w(2), at(2), 1.5_dp)
      call bound(error, 'log', w(3), at(3), 1.0_dp)
      call bound(error, 'log1p', w(4), at(4), 1.5_dp)
   end subroutine test_exp_log

   subroutine test_derived(error)
      type(error_type), allocatable, intent(out) :: error
      type(rng_type) :: rng
      real(dp) :: x, y, z, w(8), at(8), u, ls, coth, lsa(1), cotha(1)
      real(qp) :: ref
      integer :: i
      call rng%seed(12)
      w = 0.0_dp
      at = 0.0_dp
      do i = 1, nsample/2
         x = 10.0_dp**draw(rng, -300.0_dp, 300.0_dp)
         u = ulps(log10_dp(x), log10(real(x, qp)))
         if (u > w(1)) then; w(1) = u; at(1) = x; end if
         ! 10**x for the log10 of a constant
         x = draw(rng, -20.0_dp, 20.0_dp)
         u = ulps(pow10_dp(x), 10.0_qp**real(x, qp))
         if (u > w(2)) then; w(2) = u; at(2) = x; end if
         x = sign(10.0_dp**draw(rng, -10.0_dp, 10.0_dp), draw(rng, -1.0_dp, 1.0_dp))
         u = ulps(asinh_dp(x), asinh(real(x, qp)))
         if (u > w(5)) then; w(5) = u; at(5) = x; end if
         ! sinh(z)**n and its derivative over the arguments and exponents of the flow and
         ! recovery laws; as any exp(n ln s), the error of ln sinh z comes n times, and that
         ! error is of the size of its parts, z - ln2 and ln(1 - e**-2z), where their sum
         ! passes through 0 (z near 0.88): in units of max(|ln sinh z|, 1/2)
         z = 10.0_dp**draw(rng, -8.0_dp, 2.8_dp)
         y = draw(rng, 1.0_dp, 10.0_dp)
         if (y*(z + abs(log(max(z, 1.0e-300_dp)))) > 700.0_dp) cycle   ! the power overflows
         call sinh_power_dp([z], y, lsa, cotha)
         ls = lsa(1)
         coth = cotha(1)
         ref = sinh(real(z, qp))**real(y, qp)
         u = ulps(ls, ref)/(1.0_dp + y*max(abs(log(sinh(z))), 0.5_dp))
         if (u > w(6)) then; w(6) = u; at(6) = z; end if
         ref = ref*real(y, qp)*cosh(real(z, qp))/sinh(real(z, qp))
         u = ulps(coth, ref)/(1.0_dp + y*max(abs(log(sinh(z))), 0.5_dp))
         if (u > w(7)) then; w(7) = u; at(7) = z; end if
         ! the power of the flow law: the error of ln x times y, as any exp(y ln x)
         x = 10.0_dp**draw(rng, -5.0_dp, 5.0_dp)
         y = draw(rng, 1.0_dp, 10.0_dp)
         ref = real(x, qp)**real(y, qp)
         u = ulps(pow_dp(x, y), ref)/(1.0_dp + abs(y*log(x)))
         if (u > w(8)) then; w(8) = u; at(8) = x; end if
      end do
      ! Each made of two or three of exp, expm1, log and log1p: their errors add
      call bound(error, 'log10', w(1), at(1), 2.0_dp)
      call bound(error, 'pow10', w(2), at(2), 2.0_dp)
      call bound(error, 'asinh', w(5), at(5), 2.0_dp)
      ! ln sinh z within 3 (its three parts), the exponential's rounding 0.5 on top
      call bound(error, 'sinh**n / (1 + n max(|ln sinh|, 1/2))', w(6), at(6), 3.5_dp)
      call bound(error, 'd sinh**n/dz / (1 + n max(|ln sinh|, 1/2))', w(7), at(7), 3.5_dp)
      call bound(error, 'pow / (1 + |y ln x|)', w(8), at(8), 2.0_dp)
   end subroutine test_derived

   subroutine test_sincos(error)
      type(error_type), allocatable, intent(out) :: error
      type(rng_type) :: rng
      real(dp) :: u, s, c, ws, wc, ats, atc
      real(qp), parameter :: two_pi_q = 2.0_qp*acos(-1.0_qp)
      integer :: i
      call rng%seed(13)
      ws = 0.0_dp
      wc = 0.0_dp
      do i = 1, nsample
         u = draw(rng, -3.0_dp, 3.0_dp)
         call sincos_turn(u, s, c)
         ! absolute error in units of 2**-53, the scale of the angle's own rounding
         if (abs(s - sin(two_pi_q*u)) > ws*epsilon(1.0_dp)) then
            ws = real(abs(s - sin(two_pi_q*u)), dp)/epsilon(1.0_dp)
            ats = u
         end if
         if (abs(c - cos(two_pi_q*u)) > wc*epsilon(1.0_dp)) then
            wc = real(abs(c - cos(two_pi_q*u)), dp)/epsilon(1.0_dp)
            atc = u
         end if
      end do
      call bound(error, 'sin of a turn (in epsilon)', ws, ats, 1.0_dp)
      call bound(error, 'cos of a turn (in epsilon)', wc, atc, 1.0_dp)
   end subroutine test_sincos

   subroutine test_log_gamma(error)
      type(error_type), allocatable, intent(out) :: error
      type(rng_type) :: rng
      real(dp) :: x, w, at, e
      real(qp) :: ref
      integer :: i
      call rng%seed(14)
      w = 0.0_dp
      at = 0.0_dp
      do i = 1, nsample/4
         x = 10.0_dp**draw(rng, -3.0_dp, 5.0_dp)
         if (mod(i, 2) == 0) x = 0.5_dp*real(1 + mod(i, 4000), dp)   ! the chi-square shapes
         ref = log_gamma(real(x, qp))
         ! in epsilon of the result, or of ln Gamma(16) = 27.9 for x below 16, brought down
         ! from there (the result passes through 0 at 1 and 2)
         e = real(abs(log_gamma_dp(x) - ref), dp)/(epsilon(1.0_dp)*max(abs(real(ref, dp)), 27.9_dp))
         if (e > w) then
            w = e
            at = x
         end if
      end do
      call bound(error, 'log gamma (in epsilon of max(|result|, 27.9))', w, at, 4.0_dp)
   end subroutine test_log_gamma

   !> The power form of a cubic spline's pieces against the spline in its usual form (value
   !> and slope from the knots' values and second derivatives) in quadruple precision: knots
   !> of uneven spacing, values and curvatures of a measured strain's size (1e-3, 1e-3/s**2)
   subroutine test_power_form(error)
      type(error_type), allocatable, intent(out) :: error
      integer, parameter :: nk = 60
      type(rng_type) :: rng
      real(dp) :: tk(nk), vk(nk), mk(nk), c(4, nk - 1), t, u, du, eu, edu
      real(qp) :: h, a, b, ur, dur
      integer :: i, k
      call rng%seed(21)
      tk(1) = 100.0_dp
      do k = 2, nk
         tk(k) = tk(k - 1) + 10.0_dp**draw(rng, -2.0_dp, 1.0_dp)
      end do
      do k = 1, nk
         vk(k) = 1.0e-2_dp*draw(rng, -1.0_dp, 1.0_dp)
         mk(k) = 1.0e-3_dp*draw(rng, -1.0_dp, 1.0_dp)
      end do
      c = spline_power_form(tk, vk, mk)
      eu = 0.0_dp
      edu = 0.0_dp
      do i = 1, 20000
         k = 1 + mod(i, nk - 1)
         t = tk(k) + draw(rng, 0.0_dp, 1.0_dp)*(tk(k + 1) - tk(k))
         call power_piece(tk(k), c(:, k), t, u, du)
         h = real(tk(k + 1), qp) - real(tk(k), qp)
         a = (real(tk(k + 1), qp) - real(t, qp))/h
         b = 1.0_qp - a
         ur = a*vk(k) + b*vk(k + 1) + ((a**3 - a)*mk(k) + (b**3 - b)*mk(k + 1))*(h*h/6.0_qp)
         dur = (real(vk(k + 1), qp) - vk(k))/h + ((1.0_qp - 3.0_qp*a*a)*mk(k) + &
               (3.0_qp*b*b - 1.0_qp)*mk(k + 1))*(h/6.0_qp)
         ! against the size of the piece's values and slopes (1e-2, and 1e-2 over its length)
         eu = max(eu, real(abs(u - ur), dp)/1.0e-2_dp)
         edu = max(edu, real(abs(du - dur)*h, dp)/1.0e-2_dp)
      end do
      call check(error, eu < 1.0e-14_dp .and. edu < 1.0e-14_dp, 'power form of a spline: value off by '// &
                 real_str(eu, 'es9.2')//', slope by '//real_str(edu, 'es9.2')//' (relative; bound 1e-14)')
   end subroutine test_power_form

   subroutine test_special(error)
      type(error_type), allocatable, intent(out) :: error
      real(dp), parameter :: big = huge(1.0_dp)
      real(dp) :: inf, s, c
      inf = big*2.0_dp
      call check(error, exp_dp(0.0_dp) == 1.0_dp .and. log_dp(1.0_dp) == 0.0_dp .and. &
                 expm1_dp(0.0_dp) == 0.0_dp .and. log1p_dp(0.0_dp) == 0.0_dp, 'exp(0), log(1)')
      if (allocated(error)) return
      call check(error, exp_dp(710.0_dp) == inf .and. exp_dp(-746.0_dp) == 0.0_dp .and. &
                 exp_dp(-inf) == 0.0_dp .and. exp_dp(inf) == inf .and. ieee_is_finite(exp_dp(709.78_dp)) .and. &
                 exp_dp(-745.0_dp) > 0.0_dp, 'exp at the ends of its range')
      if (allocated(error)) return
      call check(error, log_dp(0.0_dp) == -inf .and. ieee_is_nan(log_dp(-1.0_dp)) .and. &
                 log_dp(inf) == inf .and. abs(log_dp(tiny(1.0_dp)*epsilon(1.0_dp)) + 744.44007192138126_dp) < 1e-12_dp, &
                 'log at 0, below 0, at infinity and of the least subnormal')
      if (allocated(error)) return
      call check(error, expm1_dp(1.0e-300_dp) == 1.0e-300_dp .and. log1p_dp(-1.0e-300_dp) == -1.0e-300_dp .and. &
                 expm1_dp(-50.0_dp) == -1.0_dp .and. log1p_dp(-1.0_dp) == -inf, 'expm1 and log1p at their ends')
      if (allocated(error)) return
      call check(error, pow10_dp(2.0_dp) == 100.0_dp .and. pow10_dp(-3.0_dp) == 1.0e-3_dp .and. &
                 pow10_dp(15.0_dp) == 1.0e15_dp .and. pow_dp(-2.0_dp, 3.0_dp) == -8.0_dp .and. &
                 ieee_is_nan(pow_dp(-2.0_dp, 0.5_dp)) .and. pow_dp(0.0_dp, 2.0_dp) == 0.0_dp .and. &
                 pow_dp(0.0_dp, -1.0_dp) == inf .and. pow_dp(5.0_dp, 0.0_dp) == 1.0_dp, 'pow and pow10')
      if (allocated(error)) return
      call check(error, asinh_dp(-3.0_dp) == -asinh_dp(3.0_dp) .and. asinh_dp(0.0_dp) == 0.0_dp, 'asinh')
      if (allocated(error)) return
      call sincos_turn(0.25_dp, s, c)
      call check(error, s == 1.0_dp .and. c == 0.0_dp, 'a quarter turn: sin 1, cos 0 exactly')
      if (allocated(error)) return
      call sincos_turn(0.5_dp, s, c)
      call check(error, s == 0.0_dp .and. c == -1.0_dp, 'a half turn: sin 0, cos -1 exactly')
      if (allocated(error)) return
      ! within 4 epsilon of ln Gamma(16), from which they are brought down (as above)
      call check(error, abs(log_gamma_dp(1.0_dp)) < 4*epsilon(1.0_dp)*27.9_dp .and. &
                 abs(log_gamma_dp(2.0_dp)) < 4*epsilon(1.0_dp)*27.9_dp .and. &
                 abs(log_gamma_dp(0.5_dp) - 0.57236494292470008707_dp) < 4*epsilon(1.0_dp)*27.9_dp, &
                 'log gamma at 1, 2, 1/2')
   end subroutine test_special

   !> No source under src/ but usharp_math calls the intrinsic exp, log, log10, sinh, cosh,
   !> tanh, asinh, sin, cos, tan, atan, erfc, gamma or log_gamma (outside comments and
   !> literals): their C library versions differ in the last bit between processors
   subroutine test_no_intrinsics(error)
      type(error_type), allocatable, intent(out) :: error
      character(len=*), parameter :: list = 'build/test-scratch/src-files.txt'
      character(len=*), parameter :: names(14) = [character(len=9) :: 'exp', 'log', 'log10', &
         'sinh', 'cosh', 'tanh', 'asinh', 'sin', 'cos', 'tan', 'atan', 'erfc', 'gamma', 'log_gamma']
      character(len=1000) :: path, line
      character(len=:), allocatable :: code, found
      integer :: lu, u, ios, ios2, stat, lineno, nfiles
      call execute_command_line('mkdir -p build/test-scratch && find src -name "*.f90" -o -name "*.inc" '// &
                                '| sort > '//list, exitstat=stat)
      call check(error, stat == 0, 'could not list the sources')
      if (allocated(error)) return
      found = ''
      nfiles = 0
      open (newunit=lu, file=list, status='old', action='read')
      do
         read (lu, '(a)', iostat=ios) path
         if (ios /= 0) exit
         if (index(path, 'usharp_math.f90') > 0) cycle
         nfiles = nfiles + 1
         open (newunit=u, file=trim(path), status='old', action='read')
         lineno = 0
         do
            read (u, '(a)', iostat=ios2) line
            if (ios2 /= 0) exit
            lineno = lineno + 1
            code = code_of(line)
            if (calls_one(code)) found = found//' '//trim(path)//':'//str(lineno)
         end do
         close (u)
      end do
      close (lu)
      call check(error, nfiles > 50, 'too few sources found')
      if (allocated(error)) return
      call check(error, len(found) == 0, 'intrinsic elementary functions called at'//found)
   contains
      !> The line without its comment and with its literals blanked
      function code_of(l) result(c)
         character(len=*), intent(in) :: l
         character(len=:), allocatable :: c
         character :: q
         integer :: i
         c = ''
         q = ' '
         do i = 1, len_trim(l)
            if (q /= ' ') then
               if (l(i:i) == q) q = ' '
               c = c//' '
            else if (l(i:i) == '!') then
               exit
            else if (l(i:i) == "'" .or. l(i:i) == '"') then
               q = l(i:i)
               c = c//' '
            else
               c = c//l(i:i)
            end if
         end do
      end function code_of
      logical function calls_one(c) result(yes)
         character(len=*), intent(in) :: c
         character(len=:), allocatable :: lc, rest
         integer :: k, i, j, n
         lc = lower(c)
         yes = .false.
         do k = 1, size(names)
            n = len_trim(names(k))
            i = 0
            do
               j = index(lc(i + 1:), trim(names(k)))
               if (j == 0) exit
               i = i + j
               if (i > 1) then
                  if (verify(lc(i - 1:i - 1), 'abcdefghijklmnopqrstuvwxyz0123456789_%') == 0) cycle
               end if
               rest = adjustl(lc(i + n:))
               if (len_trim(rest) == 0) cycle
               if (rest(1:1) == '(') yes = .true.
            end do
         end do
      end function calls_one
   end subroutine test_no_intrinsics

   !> str, real_str and join_path called from two threads at the same line at once, with
   !> results of other lengths: gfortran 12 kept a deferred-length result's length in a
   !> static variable at each call, shared by the threads (tens of thousands of torn texts in
   !> 600000 on two cores)
   subroutine test_text_threads(error)
      type(error_type), allocatable, intent(out) :: error
      integer, parameter :: ncall = 200000
      integer :: i, bad
      bad = 0
      ! (the texts are made in a procedure: a private deferred-length variable of the
      ! parallel loop itself would share its length between the threads in gfortran 12 too)
      !$omp parallel do num_threads(2) schedule(static, 1) reduction(+:bad)
      do i = 1, ncall
         bad = bad + torn(i)
      end do
      !$omp end parallel do
      call check(error, bad == 0, str(bad)//' of '//str(3*ncall)//' texts made on two threads were torn')
   contains
      !> How many of call i's three texts are not what they should be
      integer function torn(i) result(nbad)
         integer, intent(in) :: i
         character(len=:), allocatable :: a, b, c
         character(len=24) :: want
         integer :: k
         logical :: even
         ! The same lines on both threads, the one with long texts, the other short
         even = mod(i, 2) == 0
         k = merge(i*1000, mod(i, 10), even)
         a = '<'//str(k)//'>'
         b = '<'//real_str(real(k, dp), 'f0.1')//'>'
         c = join_path(trim(merge('folder', 'a/    ', even)), 'file')
         nbad = 0
         write (want, '(i0)') k
         if (a /= '<'//trim(want)//'>') nbad = nbad + 1
         if (b /= '<'//trim(want)//'.0>') nbad = nbad + 1
         if (c /= merge('folder/file', 'a/file     ', even)) nbad = nbad + 1
      end function torn
   end subroutine test_text_threads

end module test_math
