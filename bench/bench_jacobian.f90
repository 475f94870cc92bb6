!> Cost and accuracy of the two Jacobians of the residuals of the thesis's LCF + relaxation
!> fit (log10 of the seven constants) at Table 4 and at the standard guess: forward
!> differences (step 1e-3, as Levenberg-Marquardt uses them) and CVODES forward
!> sensitivities, against central differences at rtol 1e-10 (step 1e-3). One thread.
program bench_jacobian
   use, intrinsic :: iso_fortran_env, only: int64, output_unit
   use usharp_kinds, only: dp
   use usharp_error, only: error_type
   use usharp_config, only: run_config
   use usharp_input, only: read_config, override_constants
   use usharp_objective, only: fit_problem, setup_problem
   use usharp_identify, only: jacobian_log10
   implicit none
   type(run_config) :: cfg, tight
   type(fit_problem) :: prob, ptight
   type(error_type), allocatable :: e
   real(dp), allocatable :: x(:), jsens(:, :), jfd(:, :), jref(:, :), r0(:), rs(:, :), fs(:), pt(:, :), xs(:, :)
   real(dp) :: f0, tfd, tsens, cmax
   integer, allocatable :: status(:)
   character(len=1024), allocatable :: msg(:)
   integer(int64) :: c0, c1, rate
   integer :: j, k, nev, start, n, m
   integer, parameter :: nrep = 10
   logical :: ok
   write (output_unit, '(a)') '# start       Jacobian      ms     max column error   (column error: |J - J_ref| / |J_ref|,'// &
      ' columns above 1 % of the strongest)'
   do start = 1, 2
      call read_config('decks/thesis-run2.nml', cfg, e)
      if (start == 2) call override_constants(cfg, 'decks/thesis-data.nml', e)
      cfg%fit%log_search = .true.
      if (.not. allocated(e)) call setup_problem(cfg, prob, e)
      if (allocated(e)) then
         write (output_unit, '(a)') 'bench_jacobian: '//e%message
         error stop 1
      end if
      tight = cfg
      tight%solver%rtol = 1.0e-10_dp
      tight%solver%atol_strain = 1.0e-14_dp
      call setup_problem(tight, ptight, e)
      x = log10([(cfg%model%get_constant(prob%idx(j)), j=1, size(prob%idx))])
      n = size(x)
      m = prob%nres()
      call jacobian_log10(ptight, x, 1.0e-3_dp, r0, jref, f0, nev, e)
      ! Forward differences: n + 1 simulations of the test set, as in Levenberg-Marquardt
      allocate (xs(n, n + 1), rs(m, n + 1), fs(n + 1), pt(size(prob%targets), n + 1), status(n + 1), &
                msg(n + 1), jfd(m, n), jsens(m, n))
      do j = 1, n + 1
         xs(:, j) = x
         if (j > 1) xs(j - 1, j) = x(j - 1) + 1.0e-3_dp
      end do
      call system_clock(c0, rate)
      do k = 1, nrep
         call prob%batch(xs, 0, rs, fs, pt, status, msg)
      end do
      call system_clock(c1)
      tfd = real(c1 - c0, dp)/real(rate, dp)/nrep*1.0e3_dp
      do j = 1, n
         jfd(:, j) = (rs(:, j + 1) - rs(:, 1))/1.0e-3_dp
      end do
      call system_clock(c0, rate)
      do k = 1, nrep
         call prob%jacobian(x, jsens, ok)
      end do
      call system_clock(c1)
      tsens = real(c1 - c0, dp)/real(rate, dp)/nrep*1.0e3_dp
      cmax = maxval([(norm2(jref(:, j)), j=1, n)])
      write (output_unit, '(a12,a14,f8.1,es16.2)') merge('guess  ', 'Table 4', start == 1), 'difference', tfd, &
         worst(jfd)
      write (output_unit, '(a12,a14,f8.1,es16.2)') merge('guess  ', 'Table 4', start == 1), 'sensitivity', tsens, &
         worst(jsens)
      deallocate (xs, rs, fs, pt, status, msg, jfd, jsens)
   end do
contains
   real(dp) function worst(jac)
      real(dp), intent(in) :: jac(:, :)
      integer :: i
      worst = 0.0_dp
      do i = 1, size(jac, 2)
         if (norm2(jref(:, i)) < 1.0e-2_dp*cmax) cycle
         worst = max(worst, norm2(jac(:, i) - jref(:, i))/norm2(jref(:, i)))
      end do
   end function worst
end program bench_jacobian
