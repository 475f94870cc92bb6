!> Thermomechanical tests (&test tmf_temperatures, tmf_phase): the temperature follows the
!> strain command, the rates follow the temperature. Checked: a cycle between two equal
!> temperatures is the isothermal test bit for bit; the rates' time derivative (through the
!> load and the temperature) against central differences; the default tolerances against a
!> tight reference; the phase sets the loop's asymmetry; B and Q from one in-phase test with
!> 1 % noise; the input's checks. (bench/tmf.sh compares with an independent scipy reference.)
module test_tmf
   use testdrive, only: error_type, unittest_type, new_unittest, check, test_failed
   use usharp_kinds, only: dp
   use usharp_error, only: uerror => error_type
   use usharp_config, only: run_config
   use usharp_input, only: read_config
   use usharp_simulation, only: sim_result
   use usharp_simulate, only: simulate_test
   use usharp_rosenbrock_driver, only: rate_system, rates, rates_jacobian, plain_system
   use usharp_objective, only: fit_problem
   use usharp_fit, only: fit_outcome
   use test_design, only: synthetic_problem
   use test_models, only: fit_b_q_from_offset
   use test_util, only: write_text, check_message, scratch_dir
   use usharp_cmd_simulate, only: simulate_command
   use usharp_strings, only: real_str
   implicit none
   private
   public :: collect_tmf

   character(len=*), parameter :: model_lines(3) = [character(len=100) :: &
      "&model temperature = 866.15, tm = 1800.0, youngs = 22.5e3 /", &
      "&constants a1 = 0.8, a2 = 7.42e-5, b = 1.0e15, c2 = 0.1, h1 = 280.0, h2 = 100.0,", &
      "  n = 5.8, q = 91000.0 /"]

contains

   subroutine collect_tmf(testsuite)
      type(unittest_type), allocatable, intent(out) :: testsuite(:)
      testsuite = [ &
         new_unittest('tmf-equal-temperatures-is-isothermal', test_isothermal), &
         new_unittest('tmf-rates-time-derivative-fd', test_time_derivative), &
         new_unittest('tmf-against-tight-reference', test_tight), &
         new_unittest('tmf-phase-sets-the-asymmetry', test_phase), &
         new_unittest('tmf-b-and-q-from-one-test', test_b_and_q), &
         new_unittest('tmf-input-checks', test_input), &
         new_unittest('tmf-header-gives-the-starting-d0', test_header_d0), &
         new_unittest('tmf-chaboche-arrhenius-against-tight-reference', test_chaboche)]
   end subroutine collect_tmf

   !> A deck of the Miller model with one cyclic test; extra: the test's further variables
   function deck(name, extra, solver) result(path)
      character(len=*), intent(in) :: name, extra
      character(len=*), intent(in), optional :: solver
      character(len=:), allocatable :: path
      character(len=200) :: s
      s = ''
      if (present(solver)) s = solver
      path = write_text(name//'.nml', [character(len=200) :: model_lines, s, &
         "&test name = 'c', history = 'cyclic', strain_range = 0.01, strain_rate = 1e-4,", &
         "  cycles = 2, dt_out = 1.0, "//extra//" /"])
   end function deck

   subroutine simulate_deck(path, res, error)
      character(len=*), intent(in) :: path
      type(sim_result), intent(out) :: res
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: e
      type(run_config) :: cfg
      call read_config(path, cfg, e)
      if (.not. allocated(e)) call simulate_test(cfg%model, cfg%solver, cfg%tests(1), res, e)
      if (allocated(e)) call test_failed(error, e%message)
   end subroutine simulate_deck

   !> Two equal temperatures: the rates of the moved model are those of the model set up
   !> there, and no temperature term enters the time derivative
   subroutine test_isothermal(error)
      type(error_type), allocatable, intent(out) :: error
      type(sim_result) :: a, b
      call simulate_deck(deck('tmf-iso-a', 'temperature = 900.0'), a, error)
      if (allocated(error)) return
      call simulate_deck(deck('tmf-iso-b', 'tmf_temperatures = 900.0, 900.0'), b, error)
      if (allocated(error)) return
      call check(error, all(a%stress == b%stress) .and. all(a%eps_in == b%eps_in), &
                 'a cycle between 900 and 900 K differs from the test at 900 K by '// &
                 real_str(maxval(abs(a%stress - b%stress)), 'es10.3')//' ksi')
   end subroutine test_isothermal

   !> d f/d t at fixed state from rates_jacobian (the load's analytic part and the
   !> temperature's) against central differences of the rates in time, inside a segment of
   !> an in-phase cycle, at states of a simulation
   subroutine test_time_derivative(error)
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: e
      type(run_config) :: cfg
      type(sim_result) :: res
      type(rate_system) :: sys
      real(dp) :: jac(3, 3), dfdt(3), fp(3), fm(3), y(3), t, h, worst
      logical :: okp, okm
      integer :: i, k
      call read_config(deck('tmf-dfdt', 'tmf_temperatures = 811.15, 922.15'), cfg, e)
      if (.not. allocated(e)) call simulate_test(cfg%model, cfg%solver, cfg%tests(1), res, e)
      if (allocated(e)) then
         call test_failed(error, e%message)
         return
      end if
      call plain_system(cfg%model, cfg%tests(1)%hist, sys)
      worst = 0.0_dp
      ! Inside the first segments: 0-50 s rising, 50-100 s falling (corners at 50, 100 s)
      do i = 2, 90, 8
         t = real(i, dp)
         if (abs(t - 50.0_dp) < 2.0_dp) cycle
         k = merge(1, 2, t < 50.0_dp)
         sys%seg = cfg%tests(1)%hist%segment(k)
         sys%k = k
         y = [res%eps_in(i + 1), res%back(i + 1), res%drag(i + 1)]
         call rates_jacobian(sys, t, y, jac, dfdt)
         h = 1.0e-3_dp
         call rates(sys, t + h, y, fp, okp)
         call rates(sys, t - h, y, fm, okm)
         if (.not. (okp .and. okm)) then
            call test_failed(error, 'rates failed at t = '//real_str(t, 'es10.3'))
            return
         end if
         worst = max(worst, maxval(abs(dfdt - (fp - fm)/(2.0_dp*h))/(abs(dfdt) + 1.0e-3_dp*maxval(abs(dfdt)))))
      end do
      write (*, '(4x,a)') 'd f/d t against central differences: '//real_str(worst, 'es10.3')//' relative'
      call check(error, worst <= 1.0e-5_dp, 'time derivative of the rates differs from central '// &
                 'differences by '//real_str(worst, 'es10.3')//' relative')
   end subroutine test_time_derivative

   !> The default tolerances against RODAS4 at rtol 1e-10 (within 1e-4 of the peak stress),
   !> in and out of phase
   subroutine test_tight(error)
      type(error_type), allocatable, intent(out) :: error
      character(len=*), parameter :: phase(2) = ['in ', 'out']
      type(sim_result) :: a, b
      real(dp) :: dev
      integer :: k
      do k = 1, 2
         call simulate_deck(deck('tmf-tol-'//trim(phase(k)), "tmf_temperatures = 811.15, 922.15, "// &
                                 "tmf_phase = '"//trim(phase(k))//"'"), a, error)
         if (allocated(error)) return
         call simulate_deck(deck('tmf-tight-'//trim(phase(k)), "tmf_temperatures = 811.15, 922.15, "// &
                                 "tmf_phase = '"//trim(phase(k))//"'", &
                                 "&solver integrator = 'rodas4', rtol = 1e-10, atol_strain = 1e-14 /"), b, error)
         if (allocated(error)) return
         dev = maxval(abs(a%stress - b%stress))/maxval(abs(b%stress))
         write (*, '(4x,a)') trim(phase(k))//' of phase: '//real_str(dev, 'es10.3')//' of the peak from rtol 1e-10'
         call check(error, dev <= 1.0e-4_dp, trim(phase(k))//' of phase: '//real_str(dev, 'es10.3')// &
                    ' of the peak from the tight reference')
         if (allocated(error)) return
      end do
   end subroutine test_tight

   !> In phase the hot half is in tension and the tensile peak is the lower; out of phase the
   !> other way round (by more than 5 % of the peak, at 811-922 K)
   subroutine test_phase(error)
      type(error_type), allocatable, intent(out) :: error
      type(sim_result) :: a, b
      real(dp) :: ain, aout
      call simulate_deck(deck('tmf-ph-in', "tmf_temperatures = 811.15, 922.15"), a, error)
      if (allocated(error)) return
      call simulate_deck(deck('tmf-ph-out', "tmf_temperatures = 922.15, 811.15, tmf_phase = "// &
                              "'out-of-phase'"), b, error)
      if (allocated(error)) return
      ain = (maxval(a%stress) + minval(a%stress))/maxval(abs(a%stress))
      aout = (maxval(b%stress) + minval(b%stress))/maxval(abs(b%stress))
      call check(error, ain < -0.05_dp .and. aout > 0.05_dp, 'mean stress / peak: in phase '// &
                 real_str(ain, 'es10.3')//', out of phase '//real_str(aout, 'es10.3'))
   end subroutine test_phase

   !> One in-phase cycle with a hold at each temperature extreme determines B and Q together
   !> (in an isothermal test only B theta(T)); 1 % noise, from 2 B and 1.04 Q: Q within 2 %
   subroutine test_b_and_q(error)
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: e
      type(run_config) :: cfg
      type(fit_problem) :: prob
      type(fit_outcome) :: out
      real(dp), parameter :: b_true = 1.0e15_dp, q_true = 91000.0_dp
      real(dp) :: q
      call read_config(write_text('tmf-bq.nml', [character(len=100) :: model_lines, &
         "&fit fitted = 'B', 'Q', method = 'lm' /", &
         "&test name = 'tmf', history = 'cyclic', strain_range = 0.01, strain_rate = 1e-4,", &
         "  cycles = 2, hold_max = 100.0, hold_min = 100.0, dt_out = 1.0, noise = 0.01, seed = 4,", &
         "  tmf_temperatures = 811.15, 922.15 /"]), cfg, e)
      if (.not. allocated(e)) call synthetic_problem(cfg, prob, e)
      if (allocated(e)) then
         call test_failed(error, e%message)
         return
      end if
      call fit_b_q_from_offset(prob, b_true, q_true, 'tmf-bq', out, e)
      if (allocated(e)) then
         call test_failed(error, e%message)
         return
      end if
      q = out%constants(2)
      write (*, '(4x,a)') 'B '//real_str(out%constants(1), 'es10.3')//' 1/s, Q '//real_str(q, 'es10.3')//' cal/mol'
      call check(error, abs(q/q_true - 1.0_dp) <= 0.02_dp, 'Q fitted '//real_str(q, 'es10.3')//' cal/mol, true '// &
                 real_str(q_true, 'es10.3')//', B '//real_str(out%constants(1), 'es10.3'))
   end subroutine test_b_and_q

   !> The Chaboche model with an activation energy (its constants at 1223.15 K) under an
   !> out-of-phase cycle 1123.15-1223.15 K: the default tolerances against RODAS4 at rtol
   !> 1e-10 (within 1e-4 of peak), and the cycle's stresses differ from the isothermal test's
   subroutine test_chaboche(error)
      type(error_type), allocatable, intent(out) :: error
      character(len=*), parameter :: head(4) = [character(len=120) :: &
         "&model name = 'chaboche', units = 'MPa', temperature = 1223.15, tm = 1630.0,", &
         "  youngs = 144000.0, activation = 95000.0 /", &
         "&constants s0 = 10, eta = 500, n = 5, q = 30, b = 20, c1 = 8e4, g1 = 1500, c2 = 5e3,", &
         "  g2 = 60, a1 = 1e-7, m1 = 2, a2 = 1e-6, m2 = 3 /"]
      character(len=*), parameter :: cyc = "&test name = 'c', history = 'cyclic', "// &
         "strain_range = 0.01, strain_rate = 1e-4, cycles = 2, dt_out = 1.0, "
      type(sim_result) :: a, b, c
      real(dp) :: dev, diff
      call simulate_deck(write_text('tmf-ch-a.nml', [character(len=200) :: head, &
         cyc//"tmf_temperatures = 1123.15, 1223.15, tmf_phase = 'out' /"]), a, error)
      if (allocated(error)) return
      call simulate_deck(write_text('tmf-ch-b.nml', [character(len=200) :: head, &
         "&solver integrator = 'rodas4', rtol = 1e-10, atol_strain = 1e-14 /", &
         cyc//"tmf_temperatures = 1123.15, 1223.15, tmf_phase = 'out' /"]), b, error)
      if (allocated(error)) return
      call simulate_deck(write_text('tmf-ch-c.nml', [character(len=200) :: head, cyc//"/"]), c, error)
      if (allocated(error)) return
      dev = maxval(abs(a%stress - b%stress))/maxval(abs(b%stress))
      diff = maxval(abs(a%stress - c%stress))/maxval(abs(c%stress))
      write (*, '(4x,a)') 'Chaboche out of phase: '//real_str(dev, 'es10.3')//' of the peak from '// &
         'rtol 1e-10; '//real_str(diff, 'es10.3')//' of the peak from the test at 1223.15 K'
      call check(error, dev <= 1.0e-4_dp .and. diff > 0.05_dp, 'Chaboche cycle: '// &
                 real_str(dev, 'es10.3')//' of the peak from the tight reference, '// &
                 real_str(diff, 'es10.3')//' from the isothermal test')
   end subroutine test_chaboche

   !> One line naming the variable for each misuse
   subroutine test_input(error)
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: e
      type(run_config) :: cfg
      type(sim_result) :: res
      call read_config(deck('tmf-bad-both', 'temperature = 900.0, tmf_temperatures = 811.15, 922.15'), cfg, e)
      call check_message(error, e, 'temperature and tmf_temperatures are both set')
      if (allocated(error)) return
      call read_config(deck('tmf-bad-phase', "tmf_temperatures = 811.15, 922.15, tmf_phase = 'half'"), cfg, e)
      call check_message(error, e, "tmf_phase = 'half' is not known")
      if (allocated(error)) return
      call read_config(deck('tmf-bad-one', 'tmf_temperatures = 811.15'), cfg, e)
      call check_message(error, e, 'needs two temperatures')
      if (allocated(error)) return
      ! Celsius for kelvin: 20 C is below a tenth of tm
      call read_config(deck('tmf-bad-celsius', 'tmf_temperatures = 20.0, 649.0'), cfg, e)
      call check_message(error, e, 'between a tenth of tm and tm')
      if (allocated(error)) return
      call read_config(deck('tmf-above-tm', 'tmf_temperatures = 811.15, 1900.0'), cfg, e)
      call check_message(error, e, "&test #1 'c': tmf_temperatures reaches 1900.00 K, which must lie between")
      if (allocated(error)) return
      ! A Chaboche model without an activation energy: its rates do not follow the temperature,
      ! so a test at another temperature (or a cycle) would be simulated at the model's own
      block
         character(len=:), allocatable :: path
         path = write_text('tmf-chaboche-flat.nml', [character(len=120) :: &
            "&model name = 'chaboche', units = 'MPa', temperature = 1223.15, tm = 1630.0, youngs = 144000.0 /", &
            '&constants s0 = 10.0, eta = 500.0, n = 5.0, q = 30.0, b = 20.0, c1 = 8.0e4, g1 = 1500.0,', &
            '  c2 = 5.0e3, g2 = 60.0, a1 = 0.0, m1 = 1.0, a2 = 1.0e-8, m2 = 3.0 /', &
            "&test name = 't', history = 'cyclic', strain_range = 0.006, strain_rate = 1e-3, temperature = 900.0 /"])
         call read_config(path, cfg, e)
         call check_message(error, e, "&test #1 't': temperature = 900.000 K changes nothing: the rates "// &
                            'of the chaboche model here do not depend on the temperature (set &model activation)')
         if (allocated(error)) return
      end block
      call read_config(deck('tmf-cvode', 'tmf_temperatures = 811.15, 922.15', &
                            "&solver integrator = 'cvode' /"), cfg, e)
      call check_message(error, e, "&solver: integrator = 'cvode': &test #1 'c' has a temperature cycle")
      if (allocated(error)) return
      ! The simulation refuses it too, for a configuration made without the reader
      call read_config(deck('tmf-cvode-2', 'tmf_temperatures = 811.15, 922.15'), cfg, e)
      cfg%solver%integrator = 'cvode'
      if (.not. allocated(e)) call simulate_test(cfg%model, cfg%solver, cfg%tests(1), res, e)
      call check_message(error, e, "needs integrator = 'rodas4'")
   end subroutine test_input
   !> The header of a simulated temperature cycle gives D0 where the test starts (the model is
   !> set up at its first temperature), the drag the file's first row holds, not the one at
   !> the model's temperature
   subroutine test_header_d0(error)
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: e
      character(len=4096), allocatable :: written(:)
      character(len=1024) :: line
      real(dp) :: d0, row(6)
      integer :: unit, ios, k
      call simulate_command(deck('tmf-header', 'tmf_temperatures = 811.15, 922.15'), scratch_dir//'/tmf-header', &
                            written, e, force=.true.)
      if (allocated(e)) then
         call test_failed(error, e%message)
         return
      end if
      d0 = -1.0_dp
      row = -1.0_dp
      open (newunit=unit, file=trim(written(1)), status='old', action='read')
      do
         read (unit, '(a)', iostat=ios) line
         if (ios /= 0) exit
         k = index(line, 'D0 = ')
         if (line(1:1) == '#' .and. k > 0) read (line(k + 5:), *) d0
         if (line(1:1) /= '#') then
            read (line, *) row
            exit
         end if
      end do
      close (unit)
      call check(error, d0 > 0.0_dp .and. abs(d0 - row(6)) <= 1.0e-6_dp*row(6), 'header D0 '// &
                 real_str(d0, 'es14.7')//', drag of the first row '//real_str(row(6), 'es14.7'))
   end subroutine test_header_d0
end module test_tmf
