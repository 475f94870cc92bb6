!> Tail probabilities of the chi-square distribution, central and noncentral, for the power
!> of a likelihood-ratio (or BIC) test: the regularized upper incomplete gamma function by
!> its power series below a + 1 and its continued fraction above (modified Lentz), and the
!> noncentral tail as the Poisson mixture of central tails, summed about the mixture's mode
!> so that exp(-lambda/2) never underflows.
module usharp_distributions
   use usharp_kinds, only: dp
   use usharp_math, only: exp_dp, log_dp, log_gamma_dp
   implicit none
   private

   public :: gamma_q, chi2_sf, chi2_isf, ncx2_sf

   integer, parameter :: max_terms = 100000
   real(dp), parameter :: tiny_fp = 1.0e-300_dp

contains

   !> Regularized upper incomplete gamma function Q(a, x) = Gamma(a, x)/Gamma(a)
   elemental real(dp) function gamma_q(a, x) result(q)
      !> shape, > 0
      real(dp), intent(in) :: a
      !> argument, >= 0
      real(dp), intent(in) :: x
      real(dp) :: lead, term, total, b, c, d, delta, an
      integer :: n
      if (x <= 0.0_dp) then
         q = 1.0_dp
         return
      end if
      lead = exp_dp(a*log_dp(x) - x - log_gamma_dp(a))
      if (x < a + 1.0_dp) then
         ! P(a, x) = x^a e^-x / Gamma(a+1) * sum x^n / ((a+1)...(a+n))
         term = 1.0_dp/a
         total = term
         do n = 1, max_terms
            term = term*x/(a + n)
            total = total + term
            if (abs(term) < abs(total)*epsilon(1.0_dp)) exit
         end do
         q = max(0.0_dp, 1.0_dp - lead*total)
      else
         ! Q(a, x) = x^a e^-x / Gamma(a) * 1/(x+1-a- 1(1-a)/(x+3-a- 2(2-a)/(x+5-a- ...)))
         b = x + 1.0_dp - a
         c = 1.0_dp/tiny_fp
         d = 1.0_dp/b
         total = d
         do n = 1, max_terms
            an = -n*(n - a)
            b = b + 2.0_dp
            d = an*d + b
            if (abs(d) < tiny_fp) d = tiny_fp
            c = b + an/c
            if (abs(c) < tiny_fp) c = tiny_fp
            d = 1.0_dp/d
            delta = d*c
            total = total*delta
            if (abs(delta - 1.0_dp) < epsilon(1.0_dp)) exit
         end do
         q = lead*total
      end if
   end function gamma_q

   !> P(X > x) for X chi-square with k degrees of freedom
   elemental real(dp) function chi2_sf(x, k) result(p)
      real(dp), intent(in) :: x
      !> degrees of freedom, > 0
      real(dp), intent(in) :: k
      p = gamma_q(0.5_dp*k, 0.5_dp*max(x, 0.0_dp))
   end function chi2_sf

   !> The x with P(X > x) = p for X chi-square with k degrees of freedom (the critical value of
   !> a likelihood-ratio region at level 1 - p), by bisection on chi2_sf to 1e-10 of x
   elemental real(dp) function chi2_isf(p, k) result(x)
      !> upper tail probability, 0 < p < 1
      real(dp), intent(in) :: p
      !> degrees of freedom, > 0
      real(dp), intent(in) :: k
      real(dp) :: lo, hi
      integer :: it
      lo = 0.0_dp
      hi = max(1.0_dp, k)
      ! The tail falls with x: widen until it is below p
      do it = 1, 200
         if (chi2_sf(hi, k) < p) exit
         lo = hi
         hi = 2.0_dp*hi
      end do
      do it = 1, 200
         x = 0.5_dp*(lo + hi)
         if (hi - lo <= 1.0e-10_dp*max(1.0_dp, x)) exit
         if (chi2_sf(x, k) > p) then
            lo = x
         else
            hi = x
         end if
      end do
   end function chi2_isf

   !> P(X > x) for X noncentral chi-square with k degrees of freedom and noncentrality lambda
   !> (the expected chi-square of a signal: the sum of its squares over the noise variance)
   elemental real(dp) function ncx2_sf(x, k, lambda) result(p)
      real(dp), intent(in) :: x
      !> degrees of freedom, > 0
      real(dp), intent(in) :: k
      !> noncentrality, >= 0
      real(dp), intent(in) :: lambda
      real(dp) :: mu, w, sd, t
      integer :: mode, j, lo, hi
      if (lambda <= 0.0_dp) then
         p = chi2_sf(x, k)
         return
      end if
      mu = 0.5_dp*lambda
      if (mu > 1.0e7_dp) then
         ! Far past any threshold of interest: the normal limit of the mixture
         sd = sqrt(2.0_dp*(k + 2.0_dp*lambda))
         ! P(Z > t) = Q(1/2, t**2/2)/2 for t >= 0
         t = (x - k - lambda)/sd
         p = 0.5_dp*gamma_q(0.5_dp, 0.5_dp*t*t)
         if (t < 0.0_dp) p = 1.0_dp - p
         return
      end if
      ! Poisson weights e^-mu mu^j / j! about the mode, out to 12 standard deviations
      mode = int(mu)
      lo = max(0, mode - int(12.0_dp*sqrt(mu)) - 20)
      hi = mode + int(12.0_dp*sqrt(mu)) + 20
      p = 0.0_dp
      do j = lo, hi
         w = exp_dp(-mu + j*log_dp(mu) - log_gamma_dp(j + 1.0_dp))
         p = p + w*chi2_sf(x, k + 2.0_dp*j)
      end do
      p = min(1.0_dp, max(0.0_dp, p))
   end function ncx2_sf
end module usharp_distributions
