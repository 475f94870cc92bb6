!> Tests of the test-matrix design: information per test, its agreement with the intervals
!> of the identifiability report on noisy data, the enumeration of combinations, strain as
!> the response of stress-controlled tests, and the rate-jump history
module test_design
   use testdrive, only: error_type, unittest_type, new_unittest, check, test_failed
   use usharp_kinds, only: dp
   use usharp_error, only: uerror => error_type
   use usharp_config, only: run_config
   use usharp_input, only: read_config
   use usharp_history, only: history_type, rate_jump_history
   use usharp_simulation, only: sim_result
   use usharp_simulate, only: simulate_test, add_response_noise
   use usharp_experiment, only: experiment_type
   use usharp_objective, only: fit_problem, setup_problem, simulated
   use usharp_identify, only: identify_result, identify_at
   use usharp_design, only: design_result, design_run, design_report, test_information, &
                            design_combination
   use test_util, only: write_text, check_message
   use usharp_strings, only: report_line_len
   implicit none
   private
   public :: collect_design, synthetic_problem

   character(len=*), parameter :: model_groups(3) = [character(len=100) :: &
      "&model temperature = 866.15, tm = 1800.0, youngs = 22.5e3, poisson = 0.3 /", &
      "&constants a1 = 0.8, a2 = 7.42e-5, b = 1.0e15, c2 = 0.1, h1 = 280.0, h2 = 100.0,", &
      "  n = 5.8, q = 91000.0 /"]

contains

   subroutine collect_design(testsuite)
      type(unittest_type), allocatable, intent(out) :: testsuite(:)
      testsuite = [ &
         new_unittest('information-of-a-matrix-is-the-sum-over-tests', test_additive), &
         new_unittest('predicted-intervals-match-identify-on-noisy-data', test_predicted), &
         new_unittest('every-combination-ranked', test_combinations), &
         new_unittest('design-needs-a-candidate', test_no_candidate), &
         new_unittest('design-rejects-column-weights', test_column_weights), &
         new_unittest('creep-is-fitted-on-strain', test_creep_strain), &
         new_unittest('rate-jump-history', test_rate_jump), &
         new_unittest('report-columns-hold-ten-constants', test_report_columns)]
   end subroutine collect_design

   !> Synthetic data of every test of cfg from its own constants (plus the tests' noise)
   subroutine synthetic_problem(cfg, prob, e)
      type(run_config), intent(in) :: cfg
      type(fit_problem), intent(out) :: prob
      type(uerror), allocatable, intent(out) :: e
      type(experiment_type), allocatable :: exps(:)
      type(sim_result) :: sim
      integer :: i
      allocate (exps(size(cfg%tests)))
      do i = 1, size(cfg%tests)
         call simulate_test(cfg%model, cfg%solver, cfg%tests(i), sim, e)
         if (allocated(e)) return
         call add_response_noise(sim, cfg%tests(i)%hist%control, cfg%tests(i)%noise, cfg%tests(i)%seed)
         exps(i)%t = sim%t
         exps(i)%y = simulated(cfg%tests(i), sim)
      end do
      call setup_problem(cfg, prob, e, exps)
   end subroutine synthetic_problem

   !> design_run takes each test's information from a problem of that test alone; the
   !> blocks of the two-test problem's Jacobian must give the same matrices
   subroutine test_additive(error)
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: e
      type(run_config) :: cfg
      type(fit_problem) :: prob
      type(design_result) :: res
      real(dp), allocatable :: info(:, :, :)
      integer :: nevals, i
      call read_config(write_text('design-add.nml', [character(len=100) :: model_groups, &
         "&fit fitted = 'B', 'C2', 'H1', 'n' /", &
         "&test name = 'cyc', history = 'cyclic', strain_range = 0.01, strain_rate = 1e-3,", &
         "  cycles = 2, dt_out = 0.5 /", &
         "&test name = 'relax', history = 'relaxation', candidate = .true., holds = 100.0, 100.0 /"]), &
         cfg, e)
      if (.not. allocated(e)) call design_run(cfg, res, e)
      if (.not. allocated(e)) call synthetic_problem(cfg, prob, e)
      if (.not. allocated(e)) call test_information(prob, 0.01_dp, 1.0e-3_dp, info, nevals, e)
      if (allocated(e)) then
         call test_failed(error, e%message)
         return
      end if
      do i = 1, 2
         call check(error, maxval(abs(info(:, :, i) - res%info(:, :, i))) <= &
                    1.0e-8_dp*maxval(abs(info(:, :, i))), 'information of test '//char(48 + i))
         if (allocated(error)) return
         call check(error, maxval(abs(info(:, :, i))) > 0.0_dp, 'information not zero')
         if (allocated(error)) return
      end do
      ! The current matrix is the first test alone, the single addition both
      call check(error, abs(res%single(1)%logdet - res%current%logdet) > 1.0_dp, &
                 'adding relaxation gains information')
   end subroutine test_additive

   !> On data with 1 % noise, the interval that identify computes at the true constants
   !> from the residual variance must agree with the one design predicts from the noise level
   subroutine test_predicted(error)
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: e
      type(run_config) :: cfg
      type(fit_problem) :: prob
      type(design_result) :: res
      type(identify_result) :: idr
      real(dp), allocatable :: c(:), ratio(:)
      integer :: j
      call read_config(write_text('design-pred.nml', [character(len=100) :: model_groups, &
         "&fit fitted = 'B', 'H1', 'H2', 'n' /", &
         "&design noise = 0.01 /", &
         "&test name = 'cyc', history = 'cyclic', strain_range = 0.01, strain_rate = 1e-3,", &
         "  cycles = 5, dt_out = 0.05, hold_max = 300.0, noise = 0.01, seed = 5,", &
         "  candidate = .true. /"]), cfg, e)
      if (.not. allocated(e)) call design_run(cfg, res, e)
      if (.not. allocated(e)) call synthetic_problem(cfg, prob, e)
      if (allocated(e)) then
         call test_failed(error, e%message)
         return
      end if
      c = [(cfg%model%get_constant(prob%idx(j)), j=1, size(prob%idx))]
      call identify_at(prob, c, 1.0e-3_dp, idr, e)
      if (allocated(e)) then
         call test_failed(error, e%message)
         return
      end if
      ! identify's relative half-width against design's (prior negligible at these widths)
      ratio = (idr%hi95/c - 1.0_dp)/res%single(1)%half95
      call check(error, all(ratio > 0.9_dp .and. ratio < 1.1_dp), &
                 'identify/design interval ratios within 10 %')
   end subroutine test_predicted

   !> Four candidates, matrices of up to three tests: 4 + 6 + 4 combinations, best first
   subroutine test_combinations(error)
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: e
      type(run_config) :: cfg
      type(design_result) :: res
      character(len=report_line_len), allocatable :: lines(:)
      integer :: j
      call read_config(write_text('design-comb.nml', [character(len=100) :: model_groups, &
         "&fit fitted = 'B', 'C2', 'H1', 'H2', 'n' /", &
         "&design max_tests = 3, top = 20 /", &
         "&test name = 'c1', candidate = .true., history = 'cyclic', strain_range = 0.01,", &
         "  strain_rate = 1e-3, dt_out = 1.0 /", &
         "&test name = 'c2', candidate = .true., history = 'cyclic', strain_range = 0.02,", &
         "  strain_rate = 1e-3, dt_out = 1.0 /", &
         "&test name = 'r', candidate = .true., history = 'relaxation', holds = 100.0, 100.0 /", &
         "&test name = 't', candidate = .true., history = 'tensile', strain_rate = 1e-4,", &
         "  final_strain = 0.01, dt_out = 1.0 /"]), cfg, e)
      if (.not. allocated(e)) call design_run(cfg, res, e)
      if (allocated(e)) then
         call test_failed(error, e%message)
         return
      end if
      call check(error, res%ncombinations == 14 .and. size(res%best) == 14, '14 combinations')
      if (allocated(error)) return
      do j = 2, size(res%best)
         call check(error, count(res%best(j - 1)%determined) >= count(res%best(j)%determined), &
                    'ranked by constants determined')
         if (allocated(error)) return
      end do
      ! More tests never lose information: the four-test-free best triple beats its pairs
      call check(error, maxval(res%best%logdet) >= maxval(res%single%logdet), &
                 'a matrix holds at least the information of its best test')
      if (allocated(error)) return
      lines = design_report(res)
      call check(error, any(index(lines, 'recommended:') > 0), 'report recommends a matrix')
   end subroutine test_combinations

   subroutine test_no_candidate(error)
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: e
      type(run_config) :: cfg
      type(design_result) :: res
      call read_config(write_text('design-none.nml', [character(len=100) :: model_groups, &
         "&fit fitted = 'B' /", "&test name = 'r', history = 'relaxation' /"]), cfg, e)
      if (.not. allocated(e)) call design_run(cfg, res, e)
      call check_message(error, e, 'design needs at least one test with candidate = .true.')
      if (allocated(error)) return
      ! 1 % written as a whole number is 100 % of the peak: refused, the unit said
      call read_config(write_text('design-noise.nml', [character(len=100) :: model_groups, &
         "&fit fitted = 'B' /", '&design noise = 1 /', &
         "&test name = 'r', history = 'relaxation', candidate = .true. /"]), cfg, e)
      call check_message(error, e, '&design: noise = 1.000: it is a fraction of the peak '// &
                         'response, in (0, 0.5] (0.01 for 1 %)')
   end subroutine test_no_candidate

   !> Synthetic data have no weight column: a clear error, not a read of unset weights
   subroutine test_column_weights(error)
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: e
      type(run_config) :: cfg
      type(design_result) :: res
      call read_config(write_text('design-column.nml', [character(len=100) :: model_groups, &
         "&fit fitted = 'B' /", "&test name = 'r', history = 'relaxation', candidate = .true.,", &
         "  weighting = 'column', weight_column = 'w' /"]), cfg, e)
      if (.not. allocated(e)) call design_run(cfg, res, e)
      call check_message(error, e, "&test 'r': weighting = 'column' needs measured weights")
   end subroutine test_column_weights

   !> A creep test (stress control) is compared on strain: zero residual at the constants
   !> that made its data, and a non-zero sensitivity to the flow constants
   subroutine test_creep_strain(error)
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: e
      type(run_config) :: cfg
      type(fit_problem) :: prob
      real(dp), allocatable :: info(:, :, :)
      integer :: nevals
      call read_config(write_text('design-creep.nml', [character(len=100) :: model_groups, &
         "&fit fitted = 'B', 'n' /", &
         "&test name = 'creep', history = 'creep', stress = 20.0, ramp_time = 10.0,", &
         "  duration = 3600.0, dt_out = 10.0 /"]), cfg, e)
      if (.not. allocated(e)) call synthetic_problem(cfg, prob, e)
      if (.not. allocated(e)) call test_information(prob, 0.01_dp, 1.0e-3_dp, info, nevals, e)
      if (allocated(e)) then
         call test_failed(error, e%message)
         return
      end if
      call check(error, maxval(abs(prob%targets(1)%y_ex)) > 1.0e-3_dp .and. &
                 maxval(abs(prob%targets(1)%y_ex)) < 0.5_dp, 'target is a strain')
      if (allocated(error)) return
      call check(error, info(1, 1, 1) > 0.0_dp .and. info(2, 2, 1) > 0.0_dp, &
                 'B and n move the creep strain')
   end subroutine test_creep_strain

   subroutine test_rate_jump(error)
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: e
      type(history_type) :: h
      call rate_jump_history([1.0e-3_dp, 1.0e-5_dp], 0.02_dp, h, e)
      if (allocated(e)) then
         call test_failed(error, e%message)
         return
      end if
      call check(error, size(h%t) == 3, 'three corners')
      if (allocated(error)) return
      call check(error, abs(h%t(2) - 10.0_dp) < 1.0e-12_dp .and. abs(h%t(3) - 1010.0_dp) < 1.0e-9_dp &
                 .and. abs(h%v(3) - 0.02_dp) < 1.0e-15_dp, '0.01 at 1e-3/s, then 0.01 at 1e-5/s')
      if (allocated(error)) return
      call rate_jump_history([1.0e-3_dp, -1.0_dp], 0.02_dp, h, e)
      call check_message(error, e, 'rate_jump needs rates > 0')
   end subroutine test_rate_jump

   !> A model of ten fitted constants (Chaboche's): a matrix that determines all ten reads
   !> 10/10 in the det column, right-aligned under its header, as 9/10 does
   subroutine test_report_columns(error)
      type(error_type), allocatable, intent(out) :: error
      type(design_result) :: res
      type(design_combination) :: all, nine
      character(len=report_line_len), allocatable :: lines(:)
      integer :: i, k, hdr
      res%names = [character(len=4) :: 'E', 'sy', 'Q', 'b', 'C1', 'g1', 'C2', 'g2', 'K', 'n']
      res%test_names = [character(len=64) :: 'cyc1', 'cyc2']
      all%tests = [1, 2]
      all%half95 = spread(0.005_dp, 1, 10)
      all%determined = spread(.true., 1, 10)
      nine = all
      nine%tests = [1]
      nine%determined(10) = .false.
      res%current = nine
      res%single = [all]
      res%best = [all, nine]
      res%max_tests = 2
      res%ncombinations = 3
      lines = design_report(res)
      k = 0
      do i = 1, size(lines)
         if (index(lines(i), ' det ') > 0) hdr = index(lines(i), ' det ', back=.true.) + 3
         if (index(lines(i), '10/10 ') > 0) then
            k = k + 1
            call check(error, index(lines(i), '10/10 ') + 4 == hdr, '10/10 under its header: '// &
                       trim(lines(i - 1))//' / '//trim(lines(i)))
            if (allocated(error)) return
         end if
         if (index(lines(i), ' 9/10 ') > 0) then
            call check(error, index(lines(i), ' 9/10 ') + 4 == hdr, ' 9/10 under its header: '// &
                       trim(lines(i - 1))//' / '//trim(lines(i)))
            if (allocated(error)) return
         end if
      end do
      call check(error, k == 2, 'two rows of ten determined, found '//achar(48 + k))
   end subroutine test_report_columns
end module test_design
