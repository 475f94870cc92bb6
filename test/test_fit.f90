!> Tests of the fit: interpolation, weighting, objective, Hooke-Jeeves, failures, resume
module test_fit
   use testdrive, only: error_type, unittest_type, new_unittest, check, test_failed, skip_test
   use usharp_kinds, only: dp
   use usharp_error, only: uerror => error_type, stat_failure
   use usharp_experiment, only: interpolate, data_note
   use usharp_weighting, only: threshold_weights, relaxation_weights, rate_signal
   use usharp_rng, only: rng_type
   use usharp_objective, only: test_objective, fit_problem, setup_problem, eval_ok, eval_failed, &
                               eval_invalid, penalty_failed
   use usharp_simulation, only: sim_result
   use usharp_simulate, only: simulate_test
   use usharp_history, only: cyclic_history, history_type
   use usharp_rosenbrock_driver, only: simulate_rosenbrock
   use usharp_table, only: read_columns
   use usharp_filesys, only: absolute_path
   use usharp_optimiser, only: objective_type, optimum_type
   use usharp_hooke_jeeves, only: hooke_jeeves
   use usharp_config, only: run_config
   use usharp_input, only: read_config
   use usharp_cmd_run, only: run_command
   use test_util, only: write_text, usharp_exe, read_text, scratch_dir, fit_deck
   use usharp_strings, only: report_line_len, str, real_str
   implicit none
   private
   public :: collect_fit, rosenbrock

   !> Rosenbrock's function (minimum 0 at (1, 1))
   type, extends(objective_type) :: rosenbrock
      integer :: nevals = 0
   contains
      procedure :: eval => rosen_eval
   end type rosenbrock

   !> A quadratic with its minimum 0.25 at (3, -2, 0.5)
   type, extends(objective_type) :: quadratic
   contains
      procedure :: eval => quad_eval
   end type quadratic

contains

   subroutine collect_fit(testsuite)
      type(unittest_type), allocatable, intent(out) :: testsuite(:)
      testsuite = [ &
         new_unittest('interpolation-hand-values', test_interp), &
         new_unittest('threshold-weights-hand-values', test_threshold), &
         new_unittest('relaxation-weights-hand-values', test_relax_weights), &
         new_unittest('relaxation-weights-blind-to-noise', test_relax_noise), &
         new_unittest('eq7-invariant-to-resampling-eq13-not', test_resampling), &
         new_unittest('hooke-jeeves-rosenbrock', test_hj_rosenbrock), &
         new_unittest('hooke-jeeves-quadratic', test_hj_quadratic), &
         new_unittest('hooke-jeeves-honours-itermax-and-eps', test_hj_limits), &
         new_unittest('data-not-covering-span-rejected', test_coverage), &
         new_unittest('sparse-data-compared-at-its-samples', test_sparse_data), &
         new_unittest('programme-checked-against-recorded-control', test_programme), &
         new_unittest('data-unit-converted', test_units), &
         new_unittest('wrong-unit-or-column-refused', test_scale), &
         new_unittest('fit-aborts-after-failures-in-a-row', test_abort), &
         new_unittest('repeated-times-told-in-summary', test_merged_told), &
         new_unittest('kill-9-then-resume-same-result', test_resume), &
         new_unittest('peaks-target-read-and-compared', test_peaks), &
         new_unittest('peaks-and-data-share-the-objective', test_peak_share), &
         new_unittest('creep-and-lcf-in-one-deck', test_mixed), &
         new_unittest('real-a617-cycles-counted-through-gaps', test_real_life), &
         new_unittest('test-shares-joined-as-one-rank-has-them', test_shares_merged), &
         new_unittest('residual-scale-is-the-peak-within-the-simulated-time', test_peak_within), &
         new_unittest('gap-cycles-strain-in-percent-refused', test_gap_cycles_percent), &
         new_unittest('peak-file-row-written-twice-refused', test_peak_twice)]
   end subroutine collect_fit

   subroutine rosen_eval(self, x, f, error)
      class(rosenbrock), intent(inout) :: self
      real(dp), intent(in) :: x(:)
      real(dp), intent(out) :: f
      type(uerror), allocatable, intent(out) :: error
      self%nevals = self%nevals + 1
      f = 100.0_dp*(x(2) - x(1)**2)**2 + (1.0_dp - x(1))**2
   end subroutine rosen_eval

   subroutine quad_eval(self, x, f, error)
      class(quadratic), intent(inout) :: self
      real(dp), intent(in) :: x(:)
      real(dp), intent(out) :: f
      type(uerror), allocatable, intent(out) :: error
      f = 0.25_dp + (x(1) - 3.0_dp)**2 + 4.0_dp*(x(2) + 2.0_dp)**2 + 10.0_dp*(x(3) - 0.5_dp)**2 &
          + (x(1) - 3.0_dp)*(x(2) + 2.0_dp)
   end subroutine quad_eval

   subroutine test_interp(error)
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: uerr
      real(dp) :: yi(4)
      call interpolate([0.0_dp, 1.0_dp, 3.0_dp], [0.0_dp, 10.0_dp, -10.0_dp], &
                       [0.0_dp, 0.25_dp, 2.0_dp, 3.0_dp], yi, uerr)
      call check(error, .not. allocated(uerr), 'inside the data')
      if (allocated(error)) return
      call check(error, maxval(abs(yi - [0.0_dp, 2.5_dp, 0.0_dp, -10.0_dp])) < 1e-14_dp, 'hand values')
      if (allocated(error)) return
      call interpolate([0.0_dp, 1.0_dp, 3.0_dp], [0.0_dp, 10.0_dp, -10.0_dp], [0.5_dp, 3.5_dp], yi(1:2), uerr)
      call check(error, allocated(uerr), 'no extrapolation past the data')
   end subroutine test_interp

   subroutine test_threshold(error)
      type(error_type), allocatable, intent(out) :: error
      real(dp) :: w(4)
      w = threshold_weights([-15.0_dp, 13.9_dp, 14.0_dp, 20.0_dp], 14.0_dp)
      call check(error, all(w == [2.5_dp, 1.0_dp, 1.0_dp, 2.5_dp]), 'w = 2.5 above SIG, 1 below')
   end subroutine test_threshold

   !> Stress 10, 8, 7, 6.5, 6.25 at t = 0..4 s, all in a hold. By hand: s' = -1, -0.5, -0.25
   !> at points 2..4 and s'' = 1, 0.5, 0.25; the largest |s'| is at point 2, so
   !> C0 = 7/3 (1 + 1) = 14/3; w2 = (14/3 + 2)/(14/3 - 2) = 2.5, w3 = (14/3 + 1)/(14/3 - 1)
   !> = 17/11, w4 = (14/3 + 0.5)/(14/3 - 0.5) = 31/25; first and last weight 0.
   subroutine test_relax_weights(error)
      type(error_type), allocatable, intent(out) :: error
      real(dp) :: w(5)
      w = relaxation_weights([0.0_dp, 1.0_dp, 2.0_dp, 3.0_dp, 4.0_dp], &
                             [10.0_dp, 8.0_dp, 7.0_dp, 6.5_dp, 6.25_dp], spread(.true., 1, 5))
      call check(error, maxval(abs(w - [0.0_dp, 2.5_dp, 17.0_dp/11.0_dp, 31.0_dp/25.0_dp, &
                 0.0_dp])) < 1e-14_dp, 'relaxation weights by hand')
   end subroutine test_relax_weights

   !> A relaxation hold (10 + 5 exp(-t/20) MPa, 600 s at 1 s) with Gaussian noise of sd
   !> 0.05 MPa, 64 draws: weighted by its own differences, the weighted noise sum(w e**2)
   !> (Eq. 7's sum) stands 18 % above sigma**2 sum(w), since a sample its noise moves gets a
   !> larger weight; weighted by the rates of rate_signal it is sigma**2 sum(w) within the
   !> draws' scatter (0.7 %, below 1 % one standard error). Noise-free data are their own rate
   !> signal, bit for bit.
   subroutine test_relax_noise(error)
      type(error_type), allocatable, intent(out) :: error
      integer, parameter :: n = 601, ndraw = 64
      real(dp), parameter :: sigma = 0.05_dp
      real(dp) :: t(n), y(n), e(n), w(n), sum_raw, sum_new, ref_raw, ref_new
      logical :: hold(n)
      type(rng_type) :: rng
      character(len=80) :: buf
      integer :: i, k
      t = [(real(i, dp), i=0, n - 1)]
      y = 10.0_dp + 5.0_dp*exp(-t/20.0_dp)
      hold = .true.
      call check(error, all(rate_signal(t, y, [0.0_dp, 600.0_dp]) == y), 'noise-free data kept as they are')
      if (allocated(error)) return
      call rng%seed(11)
      sum_raw = 0.0_dp
      sum_new = 0.0_dp
      ref_raw = 0.0_dp
      ref_new = 0.0_dp
      do k = 1, ndraw
         do i = 1, n
            e(i) = sigma*rng%normal()
         end do
         w = relaxation_weights(t, y + e, hold)
         sum_raw = sum_raw + sum(w*e**2)
         ref_raw = ref_raw + sigma**2*sum(w)
         w = relaxation_weights(t, rate_signal(t, y + e, [0.0_dp, 600.0_dp]), hold)
         sum_new = sum_new + sum(w*e**2)
         ref_new = ref_new + sigma**2*sum(w)
      end do
      write (buf, '(a,f6.3,a,f6.3)') 'weighted noise over its expectation: raw ', &
         sum_raw/ref_raw, ', rate signal ', sum_new/ref_new
      call check(error, sum_raw/ref_raw > 1.1_dp, 'the raw differences favour noisy samples: '//trim(buf))
      if (allocated(error)) return
      call check(error, abs(sum_new/ref_new - 1.0_dp) < 0.03_dp, trim(buf))
   end subroutine test_relax_noise

   subroutine test_resampling(error)
      type(error_type), allocatable, intent(out) :: error
      real(dp), allocatable :: t1(:), t4(:)
      real(dp) :: s7a, s7b, s13a, s13b
      integer :: i
      character(len=100) :: buf
      t1 = [(real(i, dp)*0.1_dp, i=0, 100)]
      t4 = [(real(i, dp)*0.025_dp, i=0, 400)]
      s7a = test_objective('eq7', 20*sin(t1), 20*sin(t1) + cos(3*t1), 0*t1 + 1, 20.0_dp)
      s7b = test_objective('eq7', 20*sin(t4), 20*sin(t4) + cos(3*t4), 0*t4 + 1, 20.0_dp)
      s13a = test_objective('eq13', 20*sin(t1), 20*sin(t1) + cos(3*t1), 0*t1 + 1, 20.0_dp)
      s13b = test_objective('eq13', 20*sin(t4), 20*sin(t4) + cos(3*t4), 0*t4 + 1, 20.0_dp)
      write (buf, '(a,2es11.3,a,2es11.3)') 'eq7 ', s7a, s7b, ' eq13 ', s13a, s13b
      call check(error, abs(s7b/s7a - 1.0_dp) < 0.01_dp, 'Eq. 7 changes < 1 % with 4x the points: '//trim(buf))
      if (allocated(error)) return
      call check(error, abs(s13b/s13a - 4.0_dp) < 0.1_dp, 'Eq. 13 grows with the points: '//trim(buf))
   end subroutine test_resampling

   subroutine test_hj_rosenbrock(error)
      type(error_type), allocatable, intent(out) :: error
      type(rosenbrock) :: obj
      type(optimum_type) :: opt
      type(uerror), allocatable :: uerr
      call hooke_jeeves(obj, [-1.2_dp, 1.0_dp], 0.5_dp, 1.0e-8_dp, 5000, 100000, opt, uerr)
      call check(error, abs(opt%x(1) - 1.0_dp) < 1e-3_dp .and. abs(opt%x(2) - 1.0_dp) < 2e-3_dp, &
                 'Rosenbrock minimum (1, 1) found')
      if (allocated(error)) return
      call check(error, opt%f < 1e-6_dp, 'Rosenbrock value near 0')
      if (allocated(error)) return
      call check(error, opt%nevals, obj%nevals, 'evaluations counted')
   end subroutine test_hj_rosenbrock

   subroutine test_hj_quadratic(error)
      type(error_type), allocatable, intent(out) :: error
      type(quadratic) :: obj
      type(optimum_type) :: opt
      type(uerror), allocatable :: uerr
      call hooke_jeeves(obj, [0.0_dp, 0.0_dp, 0.0_dp], 0.5_dp, 1.0e-9_dp, 5000, 100000, opt, uerr)
      call check(error, maxval(abs(opt%x - [3.0_dp, -2.0_dp, 0.5_dp])) < 1e-6_dp, 'minimum at (3, -2, 0.5)')
      if (allocated(error)) return
      call check(error, opt%f, 0.25_dp, 'minimum value', thr=1e-10_dp)
   end subroutine test_hj_quadratic

   subroutine test_hj_limits(error)
      type(error_type), allocatable, intent(out) :: error
      type(rosenbrock) :: obj
      type(optimum_type) :: opt, opt2
      type(uerror), allocatable :: uerr
      call hooke_jeeves(obj, [-1.2_dp, 1.0_dp], 0.5_dp, 1.0e-8_dp, 3, 100000, opt, uerr)
      call check(error, opt%iterations, 3, 'itermax = 3 stops after 3 iterations')
      if (allocated(error)) return
      call check(error, opt%reason, 'itermax reached', 'reason')
      if (allocated(error)) return
      ! rho = 0.5: the step length falls 0.5, 0.25, ... so eps = 0.1 allows few reductions
      call hooke_jeeves(obj, [-1.2_dp, 1.0_dp], 0.5_dp, 0.1_dp, 5000, 100000, opt, uerr)
      call hooke_jeeves(obj, [-1.2_dp, 1.0_dp], 0.5_dp, 1.0e-6_dp, 5000, 100000, opt2, uerr)
      call check(error, opt%reason, 'step length <= eps', 'stopped by eps')
      if (allocated(error)) return
      call check(error, opt%nevals < opt2%nevals .and. opt%f > opt2%f, 'larger eps stops earlier')
      if (allocated(error)) return
      ! max_evals is a budget the pattern moves do not overshoot, each end of it
      call hooke_jeeves(obj, [-1.2_dp, 1.0_dp], 0.5_dp, 1.0e-8_dp, 5000, 50, opt, uerr)
      call check(error, opt%nevals <= 50 .and. opt%nevals >= 45, 'max_evals = 50 stops at 45-50 '// &
                 'evaluations, not past them')
      if (allocated(error)) return
      call check(error, opt%reason, 'max_evals reached', 'reason')
      if (allocated(error)) return
      call check(error, opt%f < 24.2_dp, 'the best point found, not the start (f = 24.2)')
   end subroutine test_hj_limits

   subroutine test_coverage(error)
      type(error_type), allocatable, intent(out) :: error
      type(run_config) :: cfg
      type(fit_problem) :: prob
      type(uerror), allocatable :: uerr
      ! The relaxation history lasts 1202 s; the LCF data cover only 240 s
      call read_config(fit_deck('cover.nml', '', [character(len=200) :: &
         "&test name='r', history='relaxation', data_file='../../data/thesis/lcf.sim.txt' /"]), cfg, uerr)
      if (.not. allocated(uerr)) call setup_problem(cfg, prob, uerr)
      call check(error, allocated(uerr), 'short data rejected')
      if (allocated(error)) return
      call check(error, index(uerr%message, 'data cover 0.00000 to 240.000 s but the '// &
                 'simulation runs from 0.00000 to 1202.00 s') > 0, uerr%message)
   end subroutine test_coverage

   !> Data sampled more coarsely than dt_out are compared only at the output times within
   !> dt_out/2 of a sample, not at values interpolated between samples (which carry no noise
   !> and make a gap the data do not hold); data at least as fine keep every output time;
   !> output times past the data's end by less than a sampling interval are left out, not
   !> refused
   subroutine test_sparse_data(error)
      type(error_type), allocatable, intent(out) :: error
      type(run_config) :: cfg
      type(fit_problem) :: prob
      character(len=:), allocatable :: f
      character(len=40), allocatable :: rows(:)
      integer :: k
      ! The relaxation history (1202 s, dt_out 1 s: 1203 output times), logged every 10 s
      rows = [character(len=40) :: 'time,stress', (str(10*k)//',10', k=0, 120), '1202,10']
      f = write_text('sparse10.csv', rows)
      call problem_of('sparse10.nml', [character(len=200) :: &
         "&test name='r', history='relaxation', data_file='sparse10.csv' /"], cfg, prob, error)
      if (allocated(error)) return
      associate (tg => prob%targets(1))
         call check(error, size(tg%t) == 122 .and. tg%exp%nunmeasured == 1081 .and. tg%exp%nbeyond == 0, &
                    'compared at the 122 samples, 1081 output times left out: '//str(size(tg%t))//' '// &
                    str(tg%exp%nunmeasured))
         if (allocated(error)) return
         call check(error, all([(minval(abs(tg%exp%t - tg%t(k))) <= 0.5_dp, k=1, size(tg%t))]), &
                    'every compared time within dt_out/2 of a sample')
         if (allocated(error)) return
         call check(error, index(data_note(tg%exp, 1.0_dp), 'not compared: 1081') > 0, &
                    'the summary says so: '//data_note(tg%exp, 1.0_dp))
         if (allocated(error)) return
      end associate
      ! Logged every second but ending at 1201 s: every output time but the last
      rows = [character(len=40) :: 'time,stress', (str(k)//',10', k=0, 1201)]
      f = write_text('dense1.csv', rows)
      call problem_of('dense1.nml', [character(len=200) :: &
         "&test name='r', history='relaxation', data_file='dense1.csv' /"], cfg, prob, error)
      if (allocated(error)) return
      associate (tg => prob%targets(1))
         call check(error, size(tg%t) == 1202 .and. tg%exp%nunmeasured == 0 .and. tg%exp%nbeyond == 1, &
                    'every output time to 1201 s compared, 1202 s left out: '//str(size(tg%t)))
      end associate
   end subroutine test_sparse_data

   !> A programmed history that is not the test the data file records (its strain column):
   !> a strain range of half the recorded one, as an amplitude given for the range makes, is
   !> refused in one line naming the variables; the right range passes
   subroutine test_programme(error)
      type(error_type), allocatable, intent(out) :: error
      type(run_config) :: cfg
      type(fit_problem) :: prob
      type(uerror), allocatable :: uerr
      real(dp), allocatable :: vals(:, :)
      character(len=60), allocatable :: rows(:)
      character(len=300) :: line(1)
      character(len=:), allocatable :: dfile
      integer :: k
      character(len=*), parameter :: test = "&test name='f', history='cyclic', strain_rate=1e-3, cycles=5, "// &
         "hold_max=600, hold_min=600, data_file='../../data/tutorial/cyclic-fast.csv', data_unit='MPa', "
      call read_config(fit_deck('programme-half.nml', '', [character(len=300) :: test//'strain_range=0.015 /']), &
                       cfg, uerr)
      if (.not. allocated(uerr)) call setup_problem(cfg, prob, uerr)
      call check(error, allocated(uerr), 'half the range refused')
      if (allocated(error)) return
      call check(error, index(uerr%message, "cyclic-fast.csv: its column 'strain'") > 0 .and. &
                 index(uerr%message, 'strain_range (max - min)') > 0, uerr%message)
      if (allocated(error)) return
      call problem_of('programme-right.nml', [character(len=300) :: test//'strain_range=0.03 /'], cfg, prob, error)
      if (allocated(error)) return
      ! The same record with its strain column in percent: refused, with the hint
      call read_columns('data/tutorial/cyclic-fast.csv', [character(len=6) :: 'time', 'strain', 'stress'], &
                        vals, uerr)
      if (allocated(uerr)) then
         call test_failed(error, uerr%message)
         return
      end if
      allocate (rows(size(vals, 1) + 1))
      rows(1) = 'time,strain,stress'
      ! A loop: an array constructor of some 6300 rows makes the compiler's memory explode
      do k = 1, size(vals, 1)
         rows(k + 1) = real_str(vals(k, 1), 'f0.3')//','//real_str(100.0_dp*vals(k, 2), 'es13.6')//','// &
                       real_str(vals(k, 3), 'f0.3')
      end do
      dfile = write_text('programme-percent.csv', rows)
      ! Through a variable: gfortran 12 sizes a typed array constructor's element made by
      ! a function of deferred length by the expression, and writes past it
      line(1) = replace_file(test, 'programme-percent.csv')//'strain_range=0.03 /'
      call read_config(fit_deck('programme-percent.nml', '', line), cfg, uerr)
      if (.not. allocated(uerr)) call setup_problem(cfg, prob, uerr)
      call check(error, allocated(uerr), 'strain in percent refused')
      if (allocated(error)) return
      call check(error, index(uerr%message, "programme-percent.csv: its column 'strain'") > 0 .and. &
                 index(uerr%message, "(from -1.500 to 1.500; strain is read as a fraction: is the column in percent?) "// &
                 "and history 'cyclic'") > 0, uerr%message)
   contains
      pure function replace_file(line, file) result(out)
         character(len=*), intent(in) :: line, file
         character(len=:), allocatable :: out
         integer :: i
         i = index(line, '../../data/tutorial/cyclic-fast.csv')
         out = line(:i - 1)//file//line(i + len('../../data/tutorial/cyclic-fast.csv'):)
      end function replace_file
   end subroutine test_programme

   subroutine test_units(error)
      type(error_type), allocatable, intent(out) :: error
      type(run_config) :: cfg
      type(fit_problem) :: prob
      character(len=:), allocatable :: dfile
      dfile = write_text('mpa.csv', [character(len=40) :: 'time,stress', '0,0', '5,68.94757293168361', '10,0'])
      dfile = write_text('mpa-strain.csv', [character(len=40) :: '0 0', '5 0.004', '10 0'])
      call problem_of('units.nml', [character(len=200) :: &
         "&test name='t', history='file', file='mpa-strain.csv', data_file='mpa.csv', data_unit='MPa' /"], &
         cfg, prob, error)
      if (allocated(error)) return
      call check(error, prob%targets(1)%y_ex_max, 10.0_dp, '68.95 MPa read as 10 ksi', thr=1e-12_dp)
   end subroutine test_units

   !> Data or a history in a wrong unit or column are refused in one line naming what: a
   !> strain range or end in percent, a creep strain in percent, a stress in GPa or one
   !> column for another, time in ms
   subroutine test_scale(error)
      type(error_type), allocatable, intent(out) :: error
      character(len=:), allocatable :: f
      character(len=40) :: rows(22)
      integer :: k
      f = write_text('scale-gpa.csv', [character(len=40) :: 'time,stress', '0,0', '60,0.21', '120,0', &
                                       '180,-0.21', '240,0'])
      ! One cycle of 120 s with its time in ms: 1 of its 21 rows within the 120 s simulated
      rows(1) = 'time,stress'
      do k = 0, 20
         rows(k + 2) = str(12000*k)//','//str(nint(30*sin(k*0.5236)))
      end do
      f = write_text('scale-ms.csv', rows)
      f = write_text('scale-creep.csv', [character(len=40) :: 'time,strain', '0,0', '50,0.3', '100,1.2'])
      call refused('scale-range.nml', "&test name='c', history='cyclic', strain_range=3.0, "// &
         "strain_rate=0.1, cycles=1 /", "history 'cyclic' reaches a strain of 1.500: strain is in mm/mm "// &
         "(is strain_range or mean_strain in percent?)")
      if (allocated(error)) return
      ! 0.5 meant as 0.5 %: a cycle of 50 % strain range, below the 100 % of any strain but
      ! beyond what a push-pull cycle reaches
      call refused('scale-range-half.nml', "&test name='c', history='cyclic', strain_range=0.5, "// &
         "strain_rate=1e-3, cycles=1 /", "history 'cyclic' reaches a strain of 0.2500, beyond the 10 % no "// &
         "push-pull cycle reaches: strain is in mm/mm (is strain_range or mean_strain in percent?)")
      if (allocated(error)) return
      call refused('scale-tensile.nml', "&test name='t', history='tensile', strain_rate=1e-3, final_strain=20.0 /", &
         "history 'tensile' reaches a strain of 20.00: strain is in mm/mm (is final_strain in percent?)")
      if (allocated(error)) return
      ! 0.21 ksi is 9.3e-6 of E = 22500 ksi: a stress of 1.45 MPa, given in GPa
      call refused('scale-gpa.nml', "&test name='c', history='cyclic', strain_range=0.01, strain_rate=1.667e-4, "// &
         "cycles=1, data_file='scale-gpa.csv' /", "scale-gpa.csv: column 'stress' peaks at 2.100E-01 ksi, "// &
         "9.3E-06 of Young's modulus (22500 ksi): is it a stress in GPa, or another column?")
      if (allocated(error)) return
      call refused('scale-ms.nml', "&test name='c', history='cyclic', strain_range=0.01, strain_rate=1.667e-4, "// &
         "cycles=1, data_file='scale-ms.csv' /", "scale-ms.csv: 4.8 % of its rows lie within the "// &
         "simulated 0.000E+00 to 1.200E+02 s (its times run to 2.400E+05 s): is the time in ms?")
      if (allocated(error)) return
      ! A creep stress in GPa (0.01 for 10 MPa, in a ksi deck 1.45 ksi): 6.4e-8 of E
      call refused('scale-creep-gpa.nml', "&test name='cr', history='creep', stress=0.00145, duration=100.0 /", &
         "&test #1 'cr': its stress reaches 1.45E-03 ksi, 6.4E-08 of Young's modulus (22500 ksi): no test of "// &
         "a metal loads it so (is the stress in GPa or a strain, not ksi?)")
      if (allocated(error)) return
      ! At the bound itself, 1e-5 of E = 144000 MPa (whose product rounds above 1.44), it passes
      block
         type(run_config) :: cfg
         type(uerror), allocatable :: uerr
         call read_config(write_text('scale-creep-bound.nml', [character(len=100) :: &
            "&model name='miller', units='MPa', temperature=866.15, tm=1800.0, youngs=144000.0 /", &
            '&constants a1=0.1, a2=1e-7, b=1e13, c2=1.0, h1=1000, h2=100, n=3.0, q=91000 /', &
            "&fit fitted='H1', 'n' /", "&test name='cr', history='creep', stress=1.44, duration=100.0 /"]), cfg, uerr)
         if (allocated(uerr)) call check(error, index(uerr%message, "Young's modulus") == 0, uerr%message)
      end block
      if (allocated(error)) return
      ! No stress at all: no unit slip to suggest
      call refused('scale-creep-zero.nml', "&test name='cr', history='creep', stress=0.0, duration=100.0 /", &
         "&test #1 'cr': its stress is 0 throughout: a stress-controlled test needs a stress")
      if (allocated(error)) return
      call refused('scale-creep.nml', "&test name='cr', history='creep', stress=10.0, duration=100.0, "// &
         "data_file='scale-creep.csv', strain_column='strain' /", &
         "scale-creep.csv: column 'strain' reaches 1.200: strain is in mm/mm (is it in percent?)")
   contains
      subroutine refused(name, test_line, message)
         character(len=*), intent(in) :: name, test_line, message
         type(run_config) :: cfg
         type(fit_problem) :: prob
         type(uerror), allocatable :: uerr
         character(len=300) :: lines(1)
         lines(1) = test_line
         call read_config(fit_deck(name, '', lines), cfg, uerr)
         if (.not. allocated(uerr)) call setup_problem(cfg, prob, uerr)
         if (.not. allocated(uerr)) then
            call test_failed(error, name//': accepted')
            return
         end if
         call check(error, index(uerr%message, message) > 0, name//': '//uerr%message)
      end subroutine refused
   end subroutine test_scale

   subroutine test_abort(error)
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: uerr
      character(len=report_line_len), allocatable :: summary(:)
      character(len=:), allocatable :: deck
      ! rho = 0.99 steps H1 and n by 99 %: with max_failures = 1 the first bad point aborts
      deck = fit_deck('abort.nml', 'max_failures=1, rho=0.99', [character(len=200) :: &
         "&test name='lcf', history='thesis_lcf', data_file='../../data/thesis/lcf.sim.txt' /"])
      call run_command(deck, scratch_dir//'/abort-out', '', .false., summary, uerr, force=.true.)
      call check(error, allocated(uerr), 'fit must abort')
      if (allocated(error)) return
      call check(error, uerr%stat, stat_failure, 'failed-fit exit category')
      if (allocated(error)) return
      call check(error, index(uerr%message, 'fit aborted: 1 failed evaluations in a row') == 1, uerr%message)
   end subroutine test_abort

   !> Data rows that repeat a time stamp are averaged as the data are read, and the summary
   !> says how many (a logger's double rows change the data the fit sees)
   subroutine test_merged_told(error)
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: uerr
      character(len=report_line_len), allocatable :: summary(:)
      character(len=:), allocatable :: deck
      integer :: stat
      ! The thesis LCF data with its 10th and 20th lines written twice
      call execute_command_line("mkdir -p "//scratch_dir//" && awk 'NR==10||NR==20{print} {print}' "// &
         "data/thesis/lcf.sim.txt > "//scratch_dir//"/lcf-twice.txt", exitstat=stat)
      call check(error, stat, 0, 'data with repeated rows written')
      if (allocated(error)) return
      deck = fit_deck('twice-rows.nml', 'max_evals=2', [character(len=200) :: &
         "&test name='lcf', history='thesis_lcf', data_file='lcf-twice.txt' /"])
      call run_command(deck, scratch_dir//'/twice-rows-out', '', .false., summary, uerr, force=.true.)
      if (allocated(uerr)) then
         call test_failed(error, uerr%message)
         return
      end if
      call check(error, any(index(summary, 'test lcf: ') > 0 .and. &
                 index(summary, 'rows repeating a time stamp of the data: 2,') > 0), 'the summary tells')
   end subroutine test_merged_told

   !> kill -9 during a run, then --resume: the same logs and result as an uninterrupted run
   subroutine test_resume(error)
      type(error_type), allocatable, intent(out) :: error
      character(len=:), allocatable :: exe, deck, full, killed, cmd
      integer :: stat
      exe = usharp_exe()
      if (len(exe) == 0) then
         call skip_test(error, 'usharp executable not found beside the test program')
         return
      end if
      deck = fit_deck('resume.nml', 'eps=1e-7', [character(len=200) :: &
         "&test name='lcf', history='thesis_lcf', data_file='../../data/thesis/lcf.sim.txt', "// &
         "weighting='threshold', sig=14 /"])
      full = scratch_dir//'/resume-full'
      killed = scratch_dir//'/resume-killed'
      call execute_command_line('rm -rf '//full//' '//killed, exitstat=stat)
      call execute_command_line(exe//' run '//deck//' -q -o '//full//' > /dev/null', exitstat=stat)
      call check(error, stat, 0, 'uninterrupted run')
      if (allocated(error)) return
      ! Start the same run, kill it hard once 30 evaluations are journalled, then resume
      cmd = exe//' run '//deck//' -q -o '//killed//' > /dev/null & pid=$!; n=0; '// &
         'while [ "$(cat '//killed//'/fit.journal 2>/dev/null | wc -l)" -lt 30 ] && [ $n -lt 3000 ]; '// &
         'do sleep 0.01; n=$((n+1)); done; kill -9 $pid; wait $pid 2>/dev/null; true'
      call execute_command_line('sh -c '''//cmd//'''', exitstat=stat)
      call check(error, len(read_text(killed//'/best.nml')) == 0, 'the killed run did not finish')
      if (allocated(error)) return
      call execute_command_line(exe//' run '//deck//' -q --resume -o '//killed//' > /dev/null', exitstat=stat)
      call check(error, stat, 0, 'resumed run')
      if (allocated(error)) return
      call check(error, len(read_text(full//'/FOM.TXT')) > 0 .and. &
                 read_text(killed//'/FOM.TXT') == read_text(full//'/FOM.TXT'), 'FOM.TXT identical')
      if (allocated(error)) return
      call check(error, read_text(killed//'/GUESS.TXT') == read_text(full//'/GUESS.TXT'), 'GUESS.TXT identical')
      if (allocated(error)) return
      call check(error, body(read_text(killed//'/best.nml')) == body(read_text(full//'/best.nml')), &
                 'best.nml identical')
   contains
      !> The text after the comment lines (which name the output folder)
      function body(text) result(rest)
         character(len=*), intent(in) :: text
         character(len=:), allocatable :: rest
         integer :: k
         k = index(text, '&constants')
         rest = text(max(k, 1):)
      end function body
   end subroutine test_resume

   !> A peak file for 3 cycles of 1 % at 1e-3/s (maxima at 5, 25, 45 s, minima at 15, 35, 55 s):
   !> four rows (the fourth cycle lies beyond the history) and a row with a missing value
   function peak_file() result(path)
      character(len=:), allocatable :: path
      path = write_text('peaks.csv', [character(len=60) :: 'cycle,time_max,max,time_min,min', &
         '1,4.5,31.5,15.0,-30.5', '2,25.0,32.0,35.0,-31.0', '3,45.0,32.5,55.0,-31.5', &
         '4,65.0,33.0,75.0,-32.0', '5,85.0,.,.,.'])
   end function peak_file

   !> A peak file with a cycle's row written twice: refused naming the rows, where the second
   !> had been counted among the peaks "at no turning point of the history"
   subroutine test_peak_twice(error)
      type(error_type), allocatable, intent(out) :: error
      type(run_config) :: cfg
      type(uerror), allocatable :: uerr
      character(len=:), allocatable :: pf
      character(len=200) :: lines(1)
      pf = write_text('peaks-twice.csv', [character(len=60) :: 'cycle,time_max,max,time_min,min', &
         '1,4.5,31.5,15.0,-30.5', '2,25.0,32.0,35.0,-31.0', '2,25.0,32.0,35.0,-31.0', '3,45.0,32.5,55.0,-31.5'])
      lines(1) = "&test name='c', history='cyclic', strain_range=0.01, strain_rate=1e-3, cycles=3, "// &
                 "target='peaks', peak_file='peaks-twice.csv' /"
      call read_config(fit_deck('peaks-twice.nml', '', lines), cfg, uerr)
      call check(error, allocated(uerr), 'a row written twice refused')
      if (allocated(error)) return
      call check(error, index(uerr%message, "peaks-twice.csv: rows 2 and 3 of those read repeat the time "// &
                 "'time_max' = 25.0") > 0, uerr%message)
   end subroutine test_peak_twice

   !> target = 'peaks': the points are the history's turning points within the file's
   !> cycles, the data the file's peak stresses, the simulation's stress there compared
   subroutine test_peaks(error)
      type(error_type), allocatable, intent(out) :: error
      type(run_config) :: cfg
      type(fit_problem) :: prob
      type(uerror), allocatable :: uerr
      type(sim_result) :: res, direct
      character(len=:), allocatable :: pf
      pf = peak_file()
      call problem_of('peaks.nml', [character(len=200) :: &
         "&test name='c', history='cyclic', strain_range=0.01, strain_rate=1e-3, cycles=3, "// &
         "target='peaks', peak_file='peaks.csv' /"], cfg, prob, error)
      if (allocated(error)) return
      associate (tg => prob%targets(1), test => cfg%tests(1))
         call check(error, all(abs(tg%t - [5.0_dp, 15.0_dp, 25.0_dp, 35.0_dp, 45.0_dp, 55.0_dp]) < 1e-12_dp), &
                    'points at the strain peaks of cycles 1 to 3')
         if (allocated(error)) return
         call check(error, all(tg%y_ex == [31.5_dp, -30.5_dp, 32.0_dp, -31.0_dp, 32.5_dp, -31.5_dp]), &
                    'measured peaks in time order')
         if (allocated(error)) return
         call check(error, all(test%peak_cycle == [1, 1, 2, 2, 3, 3]) .and. &
                    all(test%point_kind == [1, -1, 1, -1, 1, -1]), 'cycles and kinds')
         if (allocated(error)) return
         call check(error, all(tg%w == 1.0_dp) .and. tg%y_ex_max == 32.5_dp, 'weights 1, peak 32.5')
         if (allocated(error)) return
         call simulate_test(cfg%model, cfg%solver, test, res, uerr)
         if (.not. allocated(uerr)) call simulate_rosenbrock(cfg%model, test%hist, tg%t, cfg%solver, direct, uerr)
         if (allocated(uerr)) then
            call test_failed(error, uerr%message)
            return
         end if
         call check(error, all(res%stress == direct%stress), 'the stress at the peaks is compared')
      end associate
   end subroutine test_peaks

   !> target = 'both': data points and peaks, the peaks a share of the test's objective
   subroutine test_peak_share(error)
      type(error_type), allocatable, intent(out) :: error
      type(run_config) :: cfg
      type(fit_problem) :: prob
      character(len=:), allocatable :: pf, df
      integer :: n, np, i
      real(dp) :: share
      pf = peak_file()
      ! Sampled every second: every output time has a measurement (see measured_times); a
      ! stress of the cycling's strain, elastic at first and flowing at 50 ksi
      df = write_text('loops.csv', [character(len=40) :: 'time,stress', &
                      (str(i)//','//real_str(50.0_dp*tanh(22500.0_dp*0.005_dp* &
                      (1.0_dp - 4.0_dp*abs(modulo(i + 5.0_dp, 20.0_dp)/20.0_dp - 0.5_dp))/50.0_dp), 'es14.6'), &
                      i=0, 60)])
      call problem_of('both.nml', [character(len=200) :: &
         "&test name='c', history='cyclic', strain_range=0.01, strain_rate=1e-3, cycles=3, "// &
         "dt_out=2.0, target='both', peak_file='peaks.csv', data_file='loops.csv', peak_share=0.3 /"], cfg, prob, error)
      if (allocated(error)) return
      associate (tg => prob%targets(1), kind => cfg%tests(1)%point_kind)
         n = size(tg%t)
         np = count(kind /= 0)
         ! A grid of 2 s (31 points), the 6 corners off it (the peaks, at odd seconds), and the
         ! 6 peak points at the same times
         call check(error, np == 6 .and. n == 31 + 6 + 6, 'points: 37 data and 6 peaks')
         if (allocated(error)) return
         share = sum(tg%w, mask=kind /= 0)/real(n, dp)
         call check(error, share, 0.3_dp, 'peaks weigh 0.3 of the objective', thr=1e-12_dp)
         if (allocated(error)) return
         call check(error, sum(tg%w, mask=kind == 0)/real(n, dp), 0.7_dp, 'data 0.7', thr=1e-12_dp)
         if (allocated(error)) return
         call check(error, all(pack(tg%t(2:) >= tg%t(:n - 1), .true.)), 'points in time order')
      end associate
   end subroutine test_peak_share

   !> A creep test (fitted on strain) and a cyclic test (on stress) in one deck, their data
   !> made by the model: both objectives vanish at the constants that made them, and away
   !> from them each test's Eq. 7 is a percentage of its own peak, of one order
   subroutine test_mixed(error)
      type(error_type), allocatable, intent(out) :: error
      type(run_config) :: cfg
      type(fit_problem) :: prob
      type(uerror), allocatable :: uerr
      type(sim_result) :: res
      character(len=200) :: tests(2), lines(2)
      character(len=60), allocatable :: rows(:)
      character(len=:), allocatable :: msg, path
      real(dp) :: total, pt(2), x(2)
      integer :: i, k, status
      tests(1) = "&test name='creep', history='creep', stress=12.0, ramp_time=1.0, duration=3600.0, dt_out=60.0"
      tests(2) = "&test name='cyc', history='cyclic', strain_range=0.01, strain_rate=1e-3, cycles=2, dt_out=1.0"
      ! Whole lines of a fixed length (a typed constructor of trimmed texts is miscompiled)
      lines(1) = trim(tests(1))//' /'
      lines(2) = trim(tests(2))//' /'
      call read_config(fit_deck('mixed0.nml', '', lines), cfg, uerr)
      do i = 1, 2
         if (allocated(uerr)) exit
         call simulate_test(cfg%model, cfg%solver, cfg%tests(i), res, uerr)
         if (allocated(uerr)) exit
         rows = [character(len=60) :: 'time,strain,stress']
         do k = 1, size(res%t)
            rows = [character(len=60) :: rows, real_row(res%t(k), res%strain(k), res%stress(k))]
         end do
         path = write_text('mixed-'//cfg%tests(i)%name//'.csv', rows)
      end do
      lines(1) = trim(tests(1))//", data_file='mixed-creep.csv' /"
      lines(2) = trim(tests(2))//", data_file='mixed-cyc.csv' /"
      if (.not. allocated(uerr)) call read_config(fit_deck('mixed.nml', '', lines), cfg, uerr)
      if (.not. allocated(uerr)) call setup_problem(cfg, prob, uerr)
      if (allocated(uerr)) then
         call test_failed(error, uerr%message)
         return
      end if
      x = prob%start_point()
      call prob%evaluate(x, total, pt, status, msg)
      call check(error, status == eval_ok .and. maxval(pt) < 1.0e-8_dp, 'both vanish at the true constants')
      if (allocated(error)) return
      ! H1 and n 10 % off
      call prob%evaluate(1.1_dp*x, total, pt, status, msg)
      call check(error, status == eval_ok .and. minval(pt) > 1.0e-2_dp .and. maxval(pt)/minval(pt) < 1.0e3_dp, &
                 'creep and cycling weigh alike: '//real_row(pt(1), pt(2), 0.0_dp))
   contains
      function real_row(a, b, c) result(text)
         real(dp), intent(in) :: a, b, c
         character(len=60) :: text
         write (text, '(es18.10e3,",",es18.10e3,",",es18.10e3)') a, b, c
      end function real_row
   end subroutine test_mixed

   !> The measured E-12 test (1 %, 1e-3/s) from its recorded cycles 1, 2, 5, 10, 20, 50 and
   !> 99-100, the 95 cycles between them cycled through: each matched peak of its PeakStress
   !> file lies in the simulated cycle of the file's own cycle number (the fill has as many
   !> cycles as the test had), and all of cycles 1 to 100 are matched
   subroutine test_real_life(error)
      type(error_type), allocatable, intent(out) :: error
      character(len=*), parameter :: lcf = '../shared/realdata/a617-950C/lcf/'
      type(run_config) :: cfg
      type(uerror), allocatable :: uerr
      real(dp), allocatable :: rows(:, :)
      integer, allocatable :: expected(:)
      logical :: exists
      integer :: k
      inquire (file=lcf//'HTM_A19_Cycles_E12.csv', exist=exists)
      if (.not. exists) then
         call skip_test(error, 'measured data not found at '//lcf//' (shared/ not beside the checkout)')
         return
      end if
      call read_config(write_text('real-life.nml', [character(len=300) :: &
         "&model name='miller', units='MPa', temperature=1223.15, tm=1630.0, youngs=144000.0 /", &
         '&constants a1=0.116, a2=2.26e-7, b=1e15, c2=0.69, h1=1930, h2=100, n=5.8, q=91000 /', &
         "&test name='E12', history='data', dt_out=0.0, data_unit='MPa', target='peaks',", &
         "  data_file='"//absolute_path(lcf//'HTM_A19_Cycles_E12.csv')//"',", &
         "  time_column='Elapsed Time Sec', stress_column='Stress Mpa', strain_column='Strain',", &
         "  filter_column='Cycle Label', filter='Cycle 1', 'Cycle 2', 'Cycle 5', 'Cycle 10',", &
         "  'Cycle 20', 'Cycle 50', 'Cycle 99-100',", &
         "  peak_file='"//absolute_path(lcf//'HTM_A19_PeakStress_E12.csv')//"',", &
         "  peak_columns='Time Max Stress Sec', 'Max Stress Mpa', 'Time Min Stress Sec', 'Min Stress Mpa' /"]), &
         cfg, uerr)
      if (.not. allocated(uerr)) call read_columns(lcf//'HTM_A19_PeakStress_E12.csv', &
         [character(len=24) :: 'Time Max Stress Sec', 'Cycle'], rows, uerr, skip_missing=.true.)
      if (allocated(uerr)) then
         call test_failed(error, uerr%message)
         return
      end if
      associate (test => cfg%tests(1))
         ! The cycle of the file's row whose maximum lies nearest each matched maximum
         allocate (expected(size(test%tout)))
         do k = 1, size(test%tout)
            expected(k) = nint(rows(minloc(abs(rows(:, 1) - test%tout(k)), 1), 2))
         end do
         call check(error, all(pack(test%peak_cycle == expected, test%point_kind == 1)), &
                    'simulated cycle numbers are the file''s')
         if (allocated(error)) return
         call check(error, count(test%point_kind == 1) >= 99 .and. count(test%point_kind == -1) >= 99, &
                    'maxima and minima of cycles 1 to 99 matched')
      end associate
   end subroutine test_real_life
   !> An evaluation simulated in shares of its tests (ranks helping one search) and joined is
   !> the evaluation one rank makes, bit for bit; of failed shares, the first failed test in
   !> order decides the message, as it ends one rank's evaluation there
   subroutine test_shares_merged(error)
      type(error_type), allocatable, intent(out) :: error
      type(run_config) :: cfg
      type(fit_problem) :: prob
      real(dp), allocatable :: x(:), r(:), r_w(:, :), pt_w(:, :), per(:), pm(:), rm(:)
      real(dp) :: f, fw(2), fm
      integer :: status, st_w(2), fail_w(2), stm, k
      integer, parameter :: owner(3) = [1, 2, 1]
      character(len=:), allocatable :: msg, mm
      character(len=64) :: msgs(2)
      call problem_of('shares.nml', [character(len=200) :: &
         "&test name='lcf', history='thesis_lcf', data_file='../../data/thesis/lcf.sim.txt' /", &
         "&test name='relax', history='relaxation', data_file='../../data/thesis/relax.sim.txt' /", &
         "&test name='ratchet', history='ratchet', data_file='../../data/thesis/ratchet.sim.txt' /"], cfg, prob, error)
      if (allocated(error)) return
      x = prob%start_point()
      allocate (r(prob%nres()), per(3), r_w(prob%nres(), 2), pt_w(3, 2), rm(prob%nres()), pm(3))
      call prob%residuals(x, r, f, per, status, msg, 'one')
      do k = 1, 2
         call prob%residuals(x, r_w(:, k), fw(k), pt_w(:, k), st_w(k), msg, 'share', &
                             only=owner == k, failed=fail_w(k))
         msgs(k) = msg
      end do
      call prob%merge(owner, r_w, pt_w, st_w, fail_w, msgs, rm, fm, pm, stm, mm)
      call check(error, status == eval_ok .and. stm == eval_ok, 'both evaluations succeed')
      if (allocated(error)) return
      call check(error, all(rm == r) .and. fm == f .and. all(pm == per), &
                 'joined shares differ from one rank''s evaluation')
      if (allocated(error)) return
      ! Test 3 failed in one share, test 2 in the other: test 2's failure ends the evaluation
      msgs = [character(len=64) :: "test 'ratchet': integration failed", "test 'relax': integration failed"]
      call prob%merge(owner, r_w, pt_w, [eval_failed, eval_failed], [3, 2], msgs, rm, fm, pm, stm, mm)
      call check(error, stm == eval_failed .and. mm == "test 'relax': integration failed" .and. &
                 all(pm == penalty_failed) .and. all(rm == 0.0_dp), 'first failed test decides: '//mm)
      if (allocated(error)) return
      ! A share that failed beside one that did not
      call prob%merge(owner, r_w, pt_w, [eval_ok, eval_failed], [0, 2], msgs, rm, fm, pm, stm, mm)
      call check(error, stm == eval_failed .and. mm == "test 'relax': integration failed", &
                 'a failed share fails the evaluation')
      if (allocated(error)) return
      ! Invalid constants: every share found them so
      call prob%merge(owner, r_w, pt_w, [eval_invalid, eval_invalid], [0, 0], msgs, rm, fm, pm, stm, mm)
      call check(error, stm == eval_invalid, 'invalid constants stay invalid')
   end subroutine test_shares_merged

   !> The configuration and fit problem of a deck (fit_deck) with the given &test lines; a
   !> failed test when they cannot be set up
   !> A creep curve recorded to rupture (strain to 0.2, ten times what it reaches at half its
   !> life) and simulated to half its life (duration): its residuals are relative to the
   !> largest strain within the simulated time, as a prediction's RMS/peak is, not to the
   !> rupture strain the simulation never reaches
   subroutine test_peak_within(error)
      type(error_type), allocatable, intent(out) :: error
      type(run_config) :: cfg
      type(fit_problem) :: prob
      character(len=60) :: rows(42)
      character(len=200) :: lines(1)
      character(len=:), allocatable :: path
      real(dp) :: t, e
      integer :: k
      rows(1) = 'time,strain'
      do k = 0, 40
         t = 100.0_dp*real(k, dp)
         ! 0.02 at 2000 s, then ten times as fast to 0.22 at 4000 s
         e = 1.0e-5_dp*t
         if (t > 2000.0_dp) e = 0.02_dp + 1.0e-4_dp*(t - 2000.0_dp)
         rows(k + 2) = real_str(t, 'f0.1')//','//real_str(e, 'es13.6')
      end do
      path = write_text('peak-within.csv', rows)
      lines(1) = "&test name='creep', history='creep', stress=12.0, ramp_time=1.0, duration=2000.0, "// &
                 "dt_out=100.0, data_file='peak-within.csv' /"
      call problem_of('peak-within.nml', lines, cfg, prob, error)
      if (allocated(error)) return
      call check(error, abs(prob%targets(1)%y_ex_max - 0.02_dp) < 1.0e-9_dp, &
                 'scale '//real_str(prob%targets(1)%y_ex_max, 'es12.5')//', not the 0.02 reached at 2000 s')
   end subroutine test_peak_within

   !> The cycles that fill the gaps of history 'data' are checked as a programmed cycling is:
   !> strain_range = 1.0 meant as 1 % is refused naming it, and mean_strain without
   !> strain_range (which it would have been ignored without) is refused
   subroutine test_gap_cycles_percent(error)
      type(error_type), allocatable, intent(out) :: error
      type(run_config) :: cfg
      type(uerror), allocatable :: uerr
      character(len=200) :: lines(1)
      character(len=*), parameter :: test = "&test name='d', history='data', "// &
                                           "data_file='../../data/tutorial/cyclic-fast.csv', data_unit='MPa', "
      lines(1) = test//'strain_range=1.0 /'
      call read_config(fit_deck('gap-percent.nml', '', lines), cfg, uerr)
      call check(error, allocated(uerr), 'strain_range = 1.0 refused')
      if (allocated(error)) return
      call check(error, index(uerr%message, 'strain_range or mean_strain in percent') > 0 .and. &
                 index(uerr%message, 'gap-percent.nml') > 0, uerr%message)
      if (allocated(error)) return
      deallocate (uerr)
      lines(1) = test//'mean_strain=0.001 /'
      call read_config(fit_deck('gap-mean.nml', '', lines), cfg, uerr)
      call check(error, allocated(uerr), 'mean_strain alone refused')
      if (allocated(error)) return
      call check(error, index(uerr%message, 'mean_strain needs strain_range') > 0, uerr%message)
   end subroutine test_gap_cycles_percent

   subroutine problem_of(name, tests, cfg, prob, error)
      character(len=*), intent(in) :: name, tests(:)
      type(run_config), intent(out) :: cfg
      type(fit_problem), intent(out) :: prob
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: uerr
      call read_config(fit_deck(name, '', tests), cfg, uerr)
      if (.not. allocated(uerr)) call setup_problem(cfg, prob, uerr)
      if (allocated(uerr)) call test_failed(error, uerr%message)
   end subroutine problem_of

end module test_fit
