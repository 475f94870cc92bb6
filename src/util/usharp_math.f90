!> Elementary functions computed by usharp's own code, so that a result is the same bit for
!> bit on every x86-64 machine. The C library picks its exp, log, pow, sin and cos (and the
!> sinh, cosh and lgamma built on them) by the processor's features at run time (with or
!> without fused multiply-add), and they differ in the last bit; a multi-start fit amplifies
!> that into another path: another count of evaluations, another journal. Only add, multiply,
!> divide and sqrt (correctly rounded by IEEE 754) are used here, in a fixed order.
!>
!> exp: a 64-entry table of 2**(j/64) in two parts and a degree-6 polynomial on
!> |r| <= ln2/128; log: x = 2**e (1 + f) with sqrt(1/2) <= 1 + f < sqrt(2) and the series
!> of 2 atanh(f/(2 + f)). Both within about 1 unit in the last place (the test suite's math
!> suite checks every function here against quadruple precision).
module usharp_math
   use usharp_kinds, only: dp
   use, intrinsic :: iso_fortran_env, only: int64
   implicit none
   private

   public :: exp_dp, expm1_dp, log_dp, log1p_dp, log10_dp, pow_dp, pow10_dp
   public :: asinh_dp, sinh_power_dp, sincos_turn, log_gamma_dp, cubic_piece
   public :: spline_power_form, power_piece

   !> ln 2 = ln2_hi + ln2_lo, ln2_hi with 32 significant bits (so that k*ln2_hi is exact for
   !> |k| < 2**21)
   real(dp), parameter :: ln2_hi = 0.6931471803691238_dp, ln2_lo = 1.9082149292705877e-10_dp
   real(dp), parameter :: ln2 = 0.6931471805599453_dp
   !> ln 10 = ln10_hi + ln10_lo, both correctly rounded
   real(dp), parameter :: ln10_hi = 2.302585092994046_dp, ln10_lo = -2.1707562233822494e-16_dp
   real(dp), parameter :: inv_ln10 = 0.4342944819032518_dp
   real(dp), parameter :: sixty_four_over_ln2 = 92.33248261689366_dp
   real(dp), parameter :: two_pi = 6.283185307179586_dp
   real(dp), parameter :: half_log_two_pi = 0.9189385332046728_dp
   !> exp overflows above, and is below half the least subnormal under
   real(dp), parameter :: exp_max = 709.782712893384_dp, exp_min = -745.1332191019412_dp
   real(dp), parameter :: sqrt_half = 0.7071067811865476_dp
   real(dp), parameter :: pos_inf = transfer(int(z'7FF0000000000000', int64), 1.0_dp)
   real(dp), parameter :: quiet_nan = transfer(int(z'7FF8000000000000', int64), 1.0_dp)
   integer(int64), parameter :: fraction_bits = int(z'000FFFFFFFFFFFFF', int64)

   !> 2**(j/64) = tab_hi(j) + tab_lo(j), j = 0..63, each part correctly rounded
   real(dp), parameter :: tab_hi(0:63) = [ &
      1.0_dp, 1.0108892860517005_dp, 1.0218971486541166_dp, 1.0330248790212284_dp, &
      1.0442737824274138_dp, 1.0556451783605572_dp, 1.0671404006768237_dp, 1.0787607977571199_dp, &
      1.0905077326652577_dp, 1.102382583307841_dp, 1.1143867425958924_dp, 1.1265216186082418_dp, &
      1.1387886347566916_dp, 1.1511892299529827_dp, 1.1637248587775775_dp, 1.1763969916502812_dp, &
      1.189207115002721_dp, 1.202156731452703_dp, 1.215247359980469_dp, 1.22848053610687_dp, &
      1.241857812073484_dp, 1.255380757024691_dp, 1.2690509571917332_dp, 1.2828700160787783_dp, &
      1.2968395546510096_dp, 1.3109612115247644_dp, 1.3252366431597413_dp, 1.339667524053303_dp, &
      1.3542555469368927_dp, 1.3690024229745905_dp, 1.383909881963832_dp, 1.3989796725383112_dp, &
      1.4142135623730951_dp, 1.42961333839197_dp, 1.4451808069770467_dp, 1.460917794180647_dp, &
      1.4768261459394993_dp, 1.4929077282912648_dp, 1.5091644275934228_dp, 1.5255981507445384_dp, &
      1.5422108254079407_dp, 1.559004400237837_dp, 1.5759808451078865_dp, 1.593142151342267_dp, &
      1.6104903319492543_dp, 1.6280274218573478_dp, 1.645755478153965_dp, 1.6636765803267364_dp, &
      1.681792830507429_dp, 1.7001063537185235_dp, 1.718619298122478_dp, 1.7373338352737062_dp, &
      1.7562521603732995_dp, 1.7753764925265212_dp, 1.7947090750031072_dp, 1.8142521755003989_dp, &
      1.8340080864093424_dp, 1.8539791250833855_dp, 1.8741676341103_dp, 1.8945759815869656_dp, &
      1.9152065613971474_dp, 1.9360617934922943_dp, 1.9571441241754002_dp, 1.978456026387951_dp]
   real(dp), parameter :: tab_lo(0:63) = [ &
      0.0_dp, -1.5234778603368577e-17_dp, 5.109225028973444e-17_dp, &
      7.600838874027088e-18_dp, 8.551889705537965e-17_dp, 1.759325738772092e-18_dp, &
      -7.899853966841582e-17_dp, -6.656660436056593e-17_dp, -3.046782079812471e-17_dp, &
      5.2660368715706944e-17_dp, 1.0410278456845571e-16_dp, 5.165856758795457e-17_dp, &
      8.912812676025408e-17_dp, 3.250710218863827e-17_dp, 3.8292048369240935e-17_dp, &
      5.554203254218079e-17_dp, 3.982015231465646e-17_dp, 6.644981499252301e-17_dp, &
      -7.712630692681488e-17_dp, -1.89878163130253e-17_dp, 4.658027591836937e-17_dp, &
      -6.7113898212968784e-18_dp, 2.667932131342186e-18_dp, 1.713594918243561e-17_dp, &
      2.5382502794888315e-17_dp, -7.181536135519454e-17_dp, -2.8587312100388614e-17_dp, &
      8.927282594831732e-17_dp, 7.70094837980299e-17_dp, 9.593797919118849e-17_dp, &
      -6.770511658794786e-17_dp, -9.614213209051323e-17_dp, -9.667293313452913e-17_dp, &
      -1.2031642489053655e-17_dp, -3.0237581349939873e-17_dp, -5.600377186075216e-17_dp, &
      -3.483994556892796e-17_dp, 1.4192920154284036e-17_dp, -1.016455327754295e-16_dp, &
      -1.1024941712342561e-16_dp, 7.949834809697621e-17_dp, 3.7812070533575275e-17_dp, &
      -1.0136916471278304e-17_dp, -1.0094406542311964e-16_dp, 2.4707192569797888e-17_dp, &
      -6.712955084707084e-17_dp, -1.0125679913674773e-16_dp, 5.8909926967131e-17_dp, &
      8.199010020581497e-17_dp, -8.0237193703977e-18_dp, -1.851380418263111e-17_dp, &
      3.164389299292957e-17_dp, 2.960140695448873e-17_dp, 6.429731796556572e-17_dp, &
      1.8227458427912087e-17_dp, -9.969531538920349e-17_dp, 3.283107224245627e-17_dp, &
      9.761887490727594e-17_dp, -6.122763413004143e-17_dp, 3.4034035352165297e-17_dp, &
      -1.0619946056195963e-16_dp, 1.0332385960676326e-16_dp, 8.960767791036668e-17_dp, &
      4.0388753109278167e-17_dp]

contains

   !> Whether x is NaN (the only number not ordered against itself)
   elemental logical function is_nan(x)
      real(dp), intent(in) :: x
      is_nan = .not. (x <= x)
   end function is_nan

   !> Whether x is a whole number
   elemental logical function is_whole(x)
      real(dp), intent(in) :: x
      is_whole = .not. (abs(x - aint(x)) > 0.0_dp)
   end function is_whole

   !> 2**k for a normal result, -1022 <= k <= 1023, from its bits
   elemental real(dp) function two_to(k)
      integer, intent(in) :: k
      two_to = transfer(shiftl(int(k + 1023, int64), 52), 1.0_dp)
   end function two_to

   !> y 2**k for -1075 <= k <= 1024 (in two steps near the ends: a subnormal result is
   !> rounded once, in the second)
   elemental real(dp) function times_two_to(y, k) result(z)
      real(dp), intent(in) :: y
      integer, intent(in) :: k
      if (k > 1000) then
         z = (y*two_to(k - 100))*two_to(100)
      else if (k < -1000) then
         z = (y*two_to(k + 100))*two_to(-100)
      else
         z = y*two_to(k)
      end if
   end function times_two_to

   !> x = 2**e m with sqrt(1/2) <= m < sqrt(2), for a normal x > 0, from its bits
   elemental subroutine split_binary(x, m, e)
      real(dp), intent(in) :: x
      real(dp), intent(out) :: m
      integer, intent(out) :: e
      integer(int64) :: bits
      bits = transfer(x, bits)
      e = int(shiftr(bits, 52)) - 1023
      ! the same fraction with the exponent of 1: m in [1, 2)
      m = transfer(ior(iand(bits, fraction_bits), shiftl(1023_int64, 52)), 1.0_dp)
      if (m >= 1.0_dp/sqrt_half) then
         m = 0.5_dp*m
         e = e + 1
      end if
   end subroutine split_binary

   !> The parts of exp(x) = 2**k (tab_hi(j) + tab_lo(j)) (1 + p) for a finite x within the
   !> range of exp: x = (64 k + j) ln2/64 + r, |r| <= ln2/128, p = exp(r) - 1
   elemental subroutine exp_parts(x, k, j, p)
      real(dp), intent(in) :: x
      integer, intent(out) :: k, j
      real(dp), intent(out) :: p
      real(dp), parameter :: c2 = 0.5_dp, c3 = 1.0_dp/6.0_dp, c4 = 1.0_dp/24.0_dp, &
                             c5 = 1.0_dp/120.0_dp, c6 = 1.0_dp/720.0_dp
      real(dp), parameter :: shifter = 6755399441055744.0_dp   ! 1.5 2**52
      real(dp) :: r, r2, t, kn
      integer :: n
      ! kn = x 64/ln2 rounded to the nearest whole number (ties to even) by adding and
      ! taking away 1.5 2**52; its low bits are kn as an integer (|kn| < 2**17)
      t = x*sixty_four_over_ln2 + shifter
      kn = t - shifter
      n = int(transfer(t, 1_int64) - transfer(shifter, 1_int64))
      j = iand(n, 63)
      k = shifta(n, 6)       ! floor(kn/64)
      ! kn*ln2_hi/64 is exact and x lies within a factor 2 of it, so the first difference is
      ! exact too
      r = (x - kn*(ln2_hi/64.0_dp)) - kn*(ln2_lo/64.0_dp)
      ! in pairs (Estrin), for a shorter chain of dependent operations
      r2 = r*r
      p = r + r2*((c2 + r*c3) + r2*((c4 + r*c5) + r2*c6))
   end subroutine exp_parts

   !> e**x
   elemental real(dp) function exp_dp(x) result(y)
      real(dp), intent(in) :: x
      real(dp) :: p
      integer :: k, j
      if (abs(x) < 708.0_dp) then
         ! the result and 2**k are normal numbers
         call exp_parts(x, k, j, p)
         y = (tab_hi(j) + (tab_lo(j) + tab_hi(j)*p))*two_to(k)
      else if (is_nan(x)) then
         y = x
      else if (x > exp_max) then
         y = pos_inf
      else if (x < exp_min) then
         y = 0.0_dp
      else
         call exp_parts(x, k, j, p)
         y = times_two_to(tab_hi(j) + (tab_lo(j) + tab_hi(j)*p), k)
      end if
   end function exp_dp

   !> e**x - 1, accurate for small |x|
   elemental real(dp) function expm1_dp(x) result(y)
      real(dp), intent(in) :: x
      real(dp) :: p, x2, x4
      integer :: k, j
      if (is_nan(x)) then
         y = x
      else if (x > 40.0_dp) then
         y = exp_dp(x)      ! e**x > 2**57: the 1 is below its last place
      else if (x < -38.0_dp) then
         y = -1.0_dp        ! e**x < 2**-54
      else if (abs(x) < 0.5_dp*ln2) then
         ! Taylor to x**13 (the next term is below 2**-57 of the result): the table's
         ! 2**(j/64) - 1 would cancel against its correction here
         ! (in pairs, Estrin)
         x2 = x*x
         x4 = x2*x2
         y = x + x2*(((1.0_dp/2.0_dp + x*(1.0_dp/6.0_dp)) + x2*(1.0_dp/24.0_dp + x*(1.0_dp/120.0_dp))) + &
             x4*(((1.0_dp/720.0_dp + x*(1.0_dp/5040.0_dp)) + x2*(1.0_dp/40320.0_dp + x*(1.0_dp/362880.0_dp))) + &
             x4*((1.0_dp/3628800.0_dp + x*(1.0_dp/39916800.0_dp)) + &
             x2*(1.0_dp/479001600.0_dp + x*(1.0_dp/6227020800.0_dp)))))
      else
         call exp_parts(x, k, j, p)
         ! 2**k tab_hi - 1 is exact where the result is small (k = -1)
         y = (tab_hi(j)*two_to(k) - 1.0_dp) + (tab_lo(j) + tab_hi(j)*p)*two_to(k)
      end if
   end function expm1_dp

   !> ln(2**e (1 + f)) for sqrt(1/2) <= 1 + f < sqrt(2), f exact: the series of
   !> 2 atanh(s), s = f/(2 + f), as ln(1 + f) = f - f**2/2 + s (f**2/2 + r)
   elemental real(dp) function log_kernel(f, e) result(y)
      real(dp), intent(in) :: f
      integer, intent(in) :: e
      real(dp), parameter :: l1 = 2.0_dp/3.0_dp, l2 = 2.0_dp/5.0_dp, l3 = 2.0_dp/7.0_dp, &
                             l4 = 2.0_dp/9.0_dp, l5 = 2.0_dp/11.0_dp, l6 = 2.0_dp/13.0_dp, &
                             l7 = 2.0_dp/15.0_dp, l8 = 2.0_dp/17.0_dp, l9 = 2.0_dp/19.0_dp
      real(dp) :: s, z, z2, z4, r, hfsq, dk
      s = f/(2.0_dp + f)
      z = s*s
      ! (in pairs, Estrin)
      z2 = z*z
      z4 = z2*z2
      r = z*(((l1 + z*l2) + z2*(l3 + z*l4)) + z4*(((l5 + z*l6) + z2*(l7 + z*l8)) + z4*l9))
      hfsq = 0.5_dp*f*f
      dk = real(e, dp)
      y = dk*ln2_hi - ((hfsq - (s*(hfsq + r) + dk*ln2_lo)) - f)
   end function log_kernel

   !> Natural logarithm (NaN below 0, -infinity at 0)
   elemental real(dp) function log_dp(x) result(y)
      real(dp), intent(in) :: x
      real(dp) :: m
      integer :: e
      if (x >= tiny(1.0_dp) .and. x <= huge(1.0_dp)) then
         call split_binary(x, m, e)
         ! m - 1 is exact (Sterbenz)
         y = log_kernel(m - 1.0_dp, e)
      else if (is_nan(x)) then
         y = x
      else if (x < 0.0_dp) then
         y = quiet_nan
      else if (.not. (x > 0.0_dp)) then      ! 0
         y = -pos_inf
      else if (x > huge(1.0_dp)) then
         y = x
      else
         ! subnormal: scaled into the normal range first
         call split_binary(x*two_to(54), m, e)
         y = log_kernel(m - 1.0_dp, e - 54)
      end if
   end function log_dp

   !> ln(1 + x), accurate for small |x|
   elemental real(dp) function log1p_dp(x) result(y)
      real(dp), intent(in) :: x
      real(dp) :: u
      if (x >= sqrt_half - 1.0_dp .and. x < 1.0_dp/sqrt_half - 1.0_dp) then
         y = log_kernel(x, 0)
      else if (is_nan(x) .or. x <= -1.0_dp .or. x > 2.0_dp**53) then
         y = log_dp(1.0_dp + x)
      else
         ! ln(u) for the rounded u = 1 + x, and the first-order term of what the rounding
         ! lost (u - 1 is exact here)
         u = 1.0_dp + x
         y = log_dp(u) + (x - (u - 1.0_dp))/u
      end if
   end function log1p_dp

   !> Decimal logarithm
   elemental real(dp) function log10_dp(x) result(y)
      real(dp), intent(in) :: x
      y = log_dp(x)*inv_ln10
   end function log10_dp

   !> x**y for x >= 0, or x < 0 with y a whole number (NaN otherwise); by products for a
   !> whole y up to 64
   elemental real(dp) function pow_dp(x, y) result(z)
      real(dp), intent(in) :: x, y
      if (.not. (abs(y) > 0.0_dp) .or. .not. (abs(x - 1.0_dp) > 0.0_dp)) then   ! y = 0 or x = 1
         z = 1.0_dp
      else if (is_whole(y) .and. abs(y) <= 64.0_dp) then
         z = x**nint(y)     ! by products, as exact as they are
      else if (x >= 0.0_dp .or. is_nan(x)) then
         z = exp_dp(y*log_dp(x))
      else if (is_whole(y) .and. abs(y) < 2.0_dp**53) then
         z = exp_dp(y*log_dp(-x))
         if (.not. is_whole(0.5_dp*y)) z = -z
      else
         z = quiet_nan
      end if
   end function pow_dp

   !> 10**x: exact for whole x in -22..22, else from x ln10 carried to twice the precision
   elemental real(dp) function pow10_dp(x) result(y)
      real(dp), intent(in) :: x
      real(dp), parameter :: split = 134217729.0_dp   ! 2**27 + 1 (Veltkamp)
      real(dp) :: h, xa, xb, la, lb, t, err
      if (is_whole(x) .and. abs(x) <= 22.0_dp) then
         y = 10.0_dp**nint(x)
         if (x < 0.0_dp) y = 1.0_dp/10.0_dp**(-nint(x))
         return
      end if
      if (is_nan(x) .or. abs(x) > 400.0_dp) then
         y = exp_dp(x*ln10_hi)
         return
      end if
      ! h + err = x*ln10_hi exactly (Dekker's product)
      h = x*ln10_hi
      t = split*x
      xa = t - (t - x)
      xb = x - xa
      t = split*ln10_hi
      la = t - (t - ln10_hi)
      lb = ln10_hi - la
      err = ((xa*la - h) + xa*lb + xb*la) + xb*lb
      y = exp_dp(h)
      y = y + y*(err + x*ln10_lo)
   end function pow10_dp

   !> Inverse hyperbolic sine
   elemental real(dp) function asinh_dp(x) result(y)
      real(dp), intent(in) :: x
      real(dp) :: a
      a = abs(x)
      if (is_nan(x)) then
         y = x
         return
      else if (a > 2.0_dp**28) then
         y = log_dp(a) + ln2
      else if (a > 2.0_dp) then
         y = log_dp(2.0_dp*a + 1.0_dp/(sqrt(a*a + 1.0_dp) + a))
      else
         ! ln(a + sqrt(a**2 + 1)) = ln(1 + a + a**2/(1 + sqrt(1 + a**2)))
         y = log1p_dp(a + a*a/(1.0_dp + sqrt(1.0_dp + a*a)))
      end if
      y = sign(y, x)
   end function asinh_dp

   !> sinh(z)**n for 0 < z <= 700, and (if asked) its derivative n sinh(z)**n coth z, for
   !> each element of z: exp(n ln sinh z) with ln sinh z = z - ln2 + ln(1 - e**-2z) and coth z
   !> from the same e**-2z - 1, two of these functions where sinh, ln and exp would take four.
   !> The power law of the Miller model's flow and recovery, most of a simulation's time. The
   !> elements go through each function together: one element's three functions depend on
   !> one another, the elements' do not, and the processor overlaps them (the three laws of
   !> one rate evaluation 1.5 times faster than one after another; each element the same
   !> bit for bit as alone)
   pure subroutine sinh_power_dp(z, n, p, dp_dz)
      real(dp), intent(in) :: z(:)                   !< arguments, 0 < z <= 700
      real(dp), intent(in) :: n                      !< the power
      real(dp), intent(out) :: p(:)                  !< sinh(z)**n
      real(dp), intent(out), optional :: dp_dz(:)    !< n sinh(z)**n coth z
      real(dp) :: m(size(z)), l(size(z))
      integer :: i
      do i = 1, size(z)
         m(i) = expm1_dp(-2.0_dp*z(i))      ! e**-2z - 1, in (-1, 0)
      end do
      do i = 1, size(z)
         l(i) = log_dp(-m(i))
      end do
      do i = 1, size(z)
         p(i) = exp_dp(n*((z(i) - ln2) + l(i)))
      end do
      if (present(dp_dz)) dp_dz = n*p*((2.0_dp + m)/(-m))
   end subroutine sinh_power_dp

   !> sin and cos of the angle 2 pi u (u in turns), reduced exactly to an octant
   elemental subroutine sincos_turn(u, s, c)
      real(dp), intent(in) :: u
      real(dp), intent(out) :: s, c
      real(dp) :: v, a, st, ct
      logical :: neg
      ! v in [-1/2, 1/2]: exact for |u| < 2**52 (Sterbenz)
      v = u - real(nint(u, int64), dp)
      neg = v < 0.0_dp
      a = abs(v)
      if (a <= 0.125_dp) then
         call octant(two_pi*a, st, ct)
         s = st
         c = ct
      else if (a <= 0.375_dp) then
         ! 2 pi a = pi/2 - 2 pi (1/4 - a); 1/4 - a exact
         call octant(two_pi*(0.25_dp - a), st, ct)
         s = ct
         c = st
      else
         ! 2 pi a = pi - 2 pi (1/2 - a); 1/2 - a exact
         call octant(two_pi*(0.5_dp - a), st, ct)
         s = st
         c = -ct
      end if
      if (neg) s = -s
   contains
      !> sin t and cos t for |t| <= pi/4 (Taylor, to t**17 and t**16)
      elemental subroutine octant(t, st, ct)
         real(dp), intent(in) :: t
         real(dp), intent(out) :: st, ct
         real(dp) :: z
         z = t*t
         st = t + t*z*(-1.0_dp/6.0_dp + z*(1.0_dp/120.0_dp + z*(-1.0_dp/5040.0_dp + &
              z*(1.0_dp/362880.0_dp + z*(-1.0_dp/39916800.0_dp + z*(1.0_dp/6227020800.0_dp + &
              z*(-1.0_dp/1307674368000.0_dp + z*(1.0_dp/355687428096000.0_dp))))))))
         ct = 1.0_dp - 0.5_dp*z + z*z*(1.0_dp/24.0_dp + z*(-1.0_dp/720.0_dp + &
              z*(1.0_dp/40320.0_dp + z*(-1.0_dp/3628800.0_dp + z*(1.0_dp/479001600.0_dp + &
              z*(-1.0_dp/87178291200.0_dp + z*(1.0_dp/20922789888000.0_dp)))))))
      end subroutine octant
   end subroutine sincos_turn

   !> ln Gamma(x) for x > 0: Stirling's series from x + n >= 16 on, brought down by
   !> Gamma(x + 1) = x Gamma(x)
   elemental real(dp) function log_gamma_dp(x) result(y)
      real(dp), intent(in) :: x
      real(dp) :: w, z, prod, series
      if (is_nan(x) .or. x <= 0.0_dp) then
         y = quiet_nan
         return
      end if
      w = x
      prod = 1.0_dp
      do while (w < 16.0_dp)
         prod = prod*w
         w = w + 1.0_dp
      end do
      z = 1.0_dp/(w*w)
      ! Bernoulli terms B_2k/(2k (2k - 1) w**(2k - 1)), k = 1..7
      series = (1.0_dp/12.0_dp + z*(-1.0_dp/360.0_dp + z*(1.0_dp/1260.0_dp + z*(-1.0_dp/1680.0_dp + &
               z*(1.0_dp/1188.0_dp + z*(-691.0_dp/360360.0_dp + z*(1.0_dp/156.0_dp)))))))/w
      y = (w - 0.5_dp)*log_dp(w) - w + half_log_two_pi + series - log_dp(prod)
   end function log_gamma_dp

   !> Piece k (from knot k to k + 1) of the cubic spline through (tk, vk) with second
   !> derivatives mk at the knots: its value u and derivatives in t at time t (per unit of
   !> tk), the second and third if asked (the third is constant on a piece)
   pure subroutine cubic_piece(tk, vk, mk, k, t, u, du, d2u, d3u)
      real(dp), intent(in) :: tk(:), vk(:), mk(:), t
      integer, intent(in) :: k
      real(dp), intent(out) :: u, du
      real(dp), intent(out), optional :: d2u, d3u
      real(dp) :: h, a, b
      h = tk(k + 1) - tk(k)
      a = (tk(k + 1) - t)/h
      b = 1.0_dp - a
      u = a*vk(k) + b*vk(k + 1) + ((a**3 - a)*mk(k) + (b**3 - b)*mk(k + 1))*(h*h/6.0_dp)
      du = (vk(k + 1) - vk(k))/h + ((1.0_dp - 3.0_dp*a*a)*mk(k) + &
                                    (3.0_dp*b*b - 1.0_dp)*mk(k + 1))*(h/6.0_dp)
      if (present(d2u)) d2u = a*mk(k) + b*mk(k + 1)
      if (present(d3u)) d3u = (mk(k + 1) - mk(k))/h
   end subroutine cubic_piece

   !> The pieces of the cubic spline through (tk, vk) with second derivatives mk at the knots
   !> in power form: piece k is c(1,k) + s (c(2,k) + s (c(3,k) + s c(4,k))) with s = t - tk(k).
   !> Evaluated by power_piece without a division: a simulation under a measured strain
   !> evaluates its forcing at every stage of every step
   pure function spline_power_form(tk, vk, mk) result(c)
      real(dp), intent(in) :: tk(:), vk(:), mk(:)
      real(dp) :: c(4, max(size(tk) - 1, 0))
      real(dp) :: h
      integer :: k
      do k = 1, size(tk) - 1
         h = tk(k + 1) - tk(k)
         c(1, k) = vk(k)
         c(2, k) = (vk(k + 1) - vk(k))/h - h*(2.0_dp*mk(k) + mk(k + 1))/6.0_dp
         c(3, k) = 0.5_dp*mk(k)
         c(4, k) = (mk(k + 1) - mk(k))/(6.0_dp*h)
      end do
   end function spline_power_form

   !> Value u and derivative du in t at time t of one piece of a spline in power form (see
   !> spline_power_form; the same spline as cubic_piece's): tk its knot, c its coefficients.
   !> Scalars and an explicit-shape piece, no array descriptors: it runs at every stage
   pure subroutine power_piece(tk, c, t, u, du)
      real(dp), intent(in) :: tk, c(4), t
      real(dp), intent(out) :: u, du
      real(dp) :: s
      s = t - tk
      u = c(1) + s*(c(2) + s*(c(3) + s*c(4)))
      du = c(2) + s*(2.0_dp*c(3) + 3.0_dp*s*c(4))
   end subroutine power_piece
end module usharp_math
