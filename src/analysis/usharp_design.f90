!> Test-matrix design: with known constants and a noise level, how well would each
!> combination of the current tests and candidate tests determine the fitted constants?
!>
!> Every test is simulated with the known constants (its "data"); the Jacobian of its weighted
!> residuals with respect to log10 of the fitted constants gives its Fisher information
!> F_i = J_i' J_i / s_i**2, where s_i**2 is the variance the data noise gives one weighted
!> residual of the test. Information adds over tests. A weak prior (sd prior_decades in
!> log10) keeps log det finite when a matrix leaves directions undetermined. A combination's
!> predicted covariance is (P + sum F_i)^-1; a constant counts as determined when its predicted
!> 95 % interval lies within ci_target of the value. Candidates are ranked by the gain in
!> log det of the information over the current tests (D-optimality).
module usharp_design
   use usharp_kinds, only: dp
   use usharp_math, only: log10_dp, pow10_dp
   use usharp_error, only: error_type, fatal_error, prefix_error, stat_failure
   use usharp_strings, only: str, real_str, report_line_len
   use usharp_model, only: constant_names
   use usharp_config, only: run_config
   use usharp_simulation, only: sim_result
   use usharp_simulate, only: simulate_test
   use usharp_experiment, only: experiment_type
   use usharp_objective, only: fit_problem, setup_problem, simulated
   use usharp_identify, only: jacobian_log10
   use usharp_lapack, only: logdet_spd, solve_dense, mat_mul
   use usharp_fit, only: fit_fingerprint
   use usharp_task_farm, only: task_list, task_text, run_tasks
   implicit none
   private

   public :: design_result, design_combination, design_run, design_report, test_information, &
             combination_of, design_mark

   !> How design.txt begins (an earlier design's report is known by it and replaced)
   character(len=*), parameter :: design_mark = 'test-matrix design at the known constants'

   !> One test matrix: the tests (indices into the input's tests), its information and what
   !> it determines
   type :: design_combination
      integer, allocatable :: tests(:)
      real(dp) :: logdet = 0.0_dp          !< ln det of the information (prior included)
      real(dp), allocatable :: half95(:)   !< predicted relative 95 % half-width per constant
      logical, allocatable :: determined(:)
   end type design_combination

   type :: design_result
      character(len=:), allocatable :: names(:)
      character(len=64), allocatable :: test_names(:)
      logical, allocatable :: candidate(:)
      real(dp), allocatable :: info(:, :, :)     !< per-test information (p, p, ntests)
      type(design_combination) :: current          !< the current tests alone
      type(design_combination), allocatable :: single(:)  !< current + one candidate, ranked
      type(design_combination), allocatable :: best(:)    !< the best combinations, ranked
      integer :: nevals = 0, ncombinations = 0
      real(dp) :: noise = 0.0_dp, ci_target = 0.0_dp, prior_decades = 0.0_dp
      integer :: max_tests = 0
   end type design_result

   !> The tests as tasks: task i is test i's information at the known constants
   type, extends(task_list) :: design_tasks
      type(run_config) :: cfg
   contains
      procedure :: run => design_task
   end type design_tasks

contains

   !> Simulate every test with the configuration's constants and rank the candidates. The
   !> tests' information matrices are tasks spread over the MPI ranks and kept in journal
   !> ('' or absent: none; mode: see run_tasks; constants_file: the -c file, fingerprinted)
   subroutine design_run(cfg, res, error, journal, mode, constants_file)
      type(run_config), intent(in) :: cfg
      type(design_result), intent(out) :: res
      type(error_type), allocatable, intent(out) :: error
      character(len=*), intent(in), optional :: journal, mode, constants_file
      type(design_tasks) :: tasks
      type(task_text), allocatable :: results(:)
      integer :: i, j, ncur, p, nevals
      integer, allocatable :: cur(:), cand(:), fitted_idx(:)
      if (count(cfg%tests%candidate) == 0) then
         call fatal_error(error, cfg%path//': &test: design needs at least one test with '// &
                          'candidate = .true.')
         return
      end if
      ! Synthetic data carry no weight column
      do i = 1, size(cfg%tests)
         if (cfg%tests(i)%weighting == 'column') then
            call fatal_error(error, cfg%path//": &test '"//cfg%tests(i)%name//"': weighting = "// &
                             "'column' needs measured weights; design uses none, threshold or relaxation")
            return
         end if
      end do
      ncur = count(.not. cfg%tests%candidate)
      ! One test at a time: the Jacobian of a long test is large, and information adds
      tasks%cfg = cfg
      if (present(journal) .and. present(mode) .and. present(constants_file)) then
         call run_tasks(tasks, size(cfg%tests), journal, fit_fingerprint(cfg, constants_file), mode, &
                        results, error)
      else
         call run_tasks(tasks, size(cfg%tests), '', '', 'force', results, error)
      end if
      if (allocated(error)) return
      do i = 1, size(cfg%tests)
         read (results(i)%s, *) nevals, p
         if (i == 1) allocate (res%info(p, p, size(cfg%tests)))
         read (results(i)%s, *) nevals, p, res%info(:, :, i)
         res%nevals = res%nevals + nevals
      end do
      ! The indices in a variable of their own: given as the expression pack([(j, ...)], ...),
      ! gfortran 12 made constant_names blank (the report's columns had no names)
      fitted_idx = pack([(j, j=1, size(cfg%fit%fitted))], cfg%fit%fitted)
      res%names = constant_names(cfg%model, fitted_idx)
      allocate (res%test_names(size(cfg%tests)))
      do i = 1, size(cfg%tests)
         res%test_names(i) = cfg%tests(i)%name
      end do
      res%candidate = cfg%tests%candidate
      res%noise = cfg%design%noise
      res%ci_target = cfg%design%ci_target
      res%prior_decades = cfg%design%prior_decades
      res%max_tests = cfg%design%max_tests
      cur = pack([(i, i=1, size(cfg%tests))], .not. res%candidate)
      cand = pack([(i, i=1, size(cfg%tests))], res%candidate)
      res%current = combination_of(res, cur)
      allocate (res%single(size(cand)))
      do j = 1, size(cand)
         res%single(j) = combination_of(res, [cur, cand(j)])
      end do
      call rank(res%single)
      call best_combinations(res, cur, cand, max(cfg%design%max_tests - ncur, 1), &
                             cfg%design%top)
   end subroutine design_run

   !> Test k simulated with the known constants (its data) and its information; the text:
   !> 'nevals p', then the p x p matrix by columns at full precision, one number a line
   subroutine design_task(self, k, text, error)
      class(design_tasks), intent(inout) :: self
      integer, intent(in) :: k
      character(len=:), allocatable, intent(out) :: text
      type(error_type), allocatable, intent(out) :: error
      type(fit_problem) :: prob
      type(run_config) :: one
      type(experiment_type) :: exps(1)
      type(sim_result) :: sim
      real(dp), allocatable :: info1(:, :, :)
      character(len=32) :: buf
      integer :: nevals, i, j
      associate (cfg => self%cfg)
         one = cfg
         one%tests = cfg%tests(k:k)
         call simulate_test(cfg%model, cfg%solver, cfg%tests(k), sim, error)
         if (allocated(error)) then
            call prefix_error(error, cfg%path//': with the known &constants: ')
            return
         end if
         exps(1)%t = sim%t
         exps(1)%y = simulated(cfg%tests(k), sim)
         call setup_problem(one, prob, error, exps)
         if (allocated(error)) return
         call test_information(prob, cfg%design%noise, cfg%fit%fd_step, info1, nevals, error)
         if (allocated(error)) return
      end associate
      text = str(nevals)//' '//str(size(info1, 1))//new_line('a')
      do j = 1, size(info1, 2)
         do i = 1, size(info1, 1)
            write (buf, '(es25.17e3)') info1(i, j, 1)
            text = text//trim(adjustl(buf))//new_line('a')
         end do
      end do
   end subroutine design_task

   !> Fisher information of each test of prob (data = the problem's targets) in log10 of the
   !> fitted constants: J_i' J_i / s_i**2 with s_i**2 the variance of one weighted residual
   !> for a stress noise of sd noise*max|stress|
   subroutine test_information(prob, noise, h, info, nevals, error)
      type(fit_problem), intent(in) :: prob
      real(dp), intent(in) :: noise, h
      real(dp), allocatable, intent(out) :: info(:, :, :)
      integer, intent(out) :: nevals
      type(error_type), allocatable, intent(out) :: error
      type(fit_problem) :: logprob
      real(dp), allocatable :: r0(:), jac(:, :), x(:)
      real(dp) :: f0, s2, wmean
      integer :: i, j, k0, n, p
      logprob = prob
      logprob%cfg%fit%log_search = .true.
      p = size(prob%idx)
      x = [(log10_dp(prob%cfg%model%get_constant(prob%idx(j))), j=1, p)]
      call jacobian_log10(logprob, x, h, r0, jac, f0, nevals, error)
      if (allocated(error)) return
      allocate (info(p, p, size(prob%targets)))
      k0 = 0
      do i = 1, size(prob%targets)
         associate (tg => prob%targets(i))
            n = size(tg%t)
            wmean = sum(tg%w)/real(max(count(tg%w > 0.0_dp), 1), dp)
            if (prob%cfg%fit%objective == 'eq13') then
               s2 = wmean*(noise*tg%y_ex_max)**2
            else
               s2 = wmean*(100.0_dp*noise)**2/real(n, dp)
            end if
            if (s2 > 0.0_dp) then
               info(:, :, i) = mat_mul(transpose(jac(k0 + 1:k0 + n, :)), jac(k0 + 1:k0 + n, :))/s2
            else
               info(:, :, i) = 0.0_dp
            end if
            k0 = k0 + n
         end associate
      end do
   end subroutine test_information

   !> Predicted determination of the constants by the tests k(:)
   function combination_of(res, k) result(comb)
      type(design_result), intent(in) :: res
      integer, intent(in) :: k(:)
      type(design_combination) :: comb
      real(dp), allocatable :: a(:, :), cov(:, :)
      integer :: p, i, info
      p = size(res%names)
      allocate (a(p, p), cov(p, p))
      a = 0.0_dp
      do i = 1, p
         a(i, i) = 1.0_dp/res%prior_decades**2
      end do
      do i = 1, size(k)
         a = a + res%info(:, :, k(i))
      end do
      comb%tests = k
      call logdet_spd(a, comb%logdet, info)
      cov = 0.0_dp
      do i = 1, p
         cov(i, i) = 1.0_dp
      end do
      call solve_dense(a, cov, info)
      ! 95 % interval of c: c*10**(+-1.96 se) with se the sd of log10 c
      comb%half95 = [(pow10_dp(1.959963984540054_dp*sqrt(max(cov(i, i), 0.0_dp))) - 1.0_dp, &
                      i=1, p)]
      comb%determined = comb%half95 <= res%ci_target
   end function combination_of

   !> Every combination of up to nmax candidates with the current tests; the top best kept
   subroutine best_combinations(res, cur, cand, nmax, top)
      type(design_result), intent(inout) :: res
      integer, intent(in) :: cur(:), cand(:), nmax, top
      type(design_combination), allocatable :: all(:)
      integer :: pick(nmax), m, nall, r
      nall = 0
      allocate (all(0))
      do r = 1, min(nmax, size(cand))
         ! Lexicographic r-subsets of the candidates
         pick(1:r) = [(m, m=1, r)]
         do
            call append(all, nall, combination_of(res, [cur, cand(pick(1:r))]))
            m = r
            do while (m >= 1)
               if (pick(m) < size(cand) - r + m) exit
               m = m - 1
            end do
            if (m < 1) exit
            pick(m) = pick(m) + 1
            call refill(pick, m, r)
         end do
      end do
      call rank(all(:nall))
      res%ncombinations = nall
      res%best = all(:min(top, nall))
   end subroutine best_combinations

   !> After pick(m) advanced, the following picks run on consecutively
   pure subroutine refill(pick, m, r)
      integer, intent(inout) :: pick(:)
      integer, intent(in) :: m, r
      integer :: k
      do k = m + 1, r
         pick(k) = pick(k - 1) + 1
      end do
   end subroutine refill

   subroutine append(list, n, item)
      type(design_combination), allocatable, intent(inout) :: list(:)
      integer, intent(inout) :: n
      type(design_combination), intent(in) :: item
      type(design_combination), allocatable :: tmp(:)
      integer :: k
      if (n == size(list)) then
         allocate (tmp(max(16, 2*n)))
         do k = 1, n
            tmp(k) = list(k)
         end do
         call move_alloc(tmp, list)
      end if
      n = n + 1
      list(n) = item
   end subroutine append

   !> Order: most constants determined first, then the smaller worst predicted interval, then
   !> the larger log det
   subroutine rank(list)
      type(design_combination), intent(inout) :: list(:)
      type(design_combination) :: key
      integer :: i, j
      do i = 2, size(list)
         key = list(i)
         j = i - 1
         do while (j >= 1)
            if (.not. before(key, list(j))) exit
            list(j + 1) = list(j)
            j = j - 1
         end do
         list(j + 1) = key
      end do
   end subroutine rank

   pure logical function before(a, b)
      type(design_combination), intent(in) :: a, b
      if (count(a%determined) /= count(b%determined)) then
         before = count(a%determined) > count(b%determined)
      else if (maxval(a%half95) /= maxval(b%half95)) then
         before = maxval(a%half95) < maxval(b%half95)
      else
         before = a%logdet > b%logdet
      end if
   end function before

   !> The design as lines of text
   function design_report(res) result(lines)
      type(design_result), intent(in) :: res
      character(len=report_line_len), allocatable :: lines(:)
      integer :: j
      lines = [character(len=report_line_len) :: design_mark//': stress noise sd '// &
         percent(res%noise, 'f0.2')//' % of each test''s peak, determined = predicted '// &
         '95 % interval within '//percent(res%ci_target, 'f0.1')//' %', &
         '  (information in log10 of the constants; prior sd '//real_str(res%prior_decades, 'f0.1')// &
         ' decades; '//str(res%nevals)//' simulations of single tests; predicted 95 % half-widths in %)', '']
      lines = [character(len=report_line_len) :: lines, '  current tests: '//test_list(res, res%current%tests)]
      lines = [character(len=report_line_len) :: lines, header(res, 'gain'), &
         row(res, res%current, 0.0_dp, 'current')]
      lines = [character(len=report_line_len) :: lines, '', '  each candidate added to the current tests, '// &
         'ranked by constants determined, then the widest interval, then the gain in ln det:', &
         header(res, 'gain')]
      do j = 1, size(res%single)
         lines = [character(len=report_line_len) :: lines, row(res, res%single(j), &
            res%single(j)%logdet - res%current%logdet, &
            test_list(res, res%single(j)%tests(size(res%single(j)%tests):)))]
      end do
      lines = [character(len=report_line_len) :: lines, '', '  best test matrices of up to '// &
         str(res%max_tests)//' tests ('//str(res%ncombinations)//' combinations; ranked by '// &
         'constants determined, then the widest interval):', header(res, 'ln det')]
      do j = 1, size(res%best)
         lines = [character(len=report_line_len) :: lines, row(res, res%best(j), res%best(j)%logdet, &
            test_list(res, res%best(j)%tests))]
      end do
      if (size(res%best) > 0) then
         lines = [character(len=report_line_len) :: lines, '', '  recommended: '// &
            test_list(res, res%best(1)%tests)//': '//determined_words(res, res%best(1))]
      end if
   contains
      !> A fraction as a percentage in fmt, or in three significant digits below 0.1 %
      pure function percent(fraction, fmt) result(text)
         real(dp), intent(in) :: fraction
         character(len=*), intent(in) :: fmt
         character(len=:), allocatable :: text
         if (100.0_dp*fraction >= 0.1_dp) then
            text = real_str(100.0_dp*fraction, fmt)
         else
            text = real_str(100.0_dp*fraction, 'es9.2')
         end if
      end function percent
   end function design_report

   function header(res, what) result(line)
      type(design_result), intent(in) :: res
      character(len=*), intent(in) :: what
      character(len=:), allocatable :: line
      integer :: j
      character(len=9) :: col
      character(len=6) :: name
      col = what
      col = adjustr(col)
      line = '    '//col//'   det'
      do j = 1, size(res%names)
         ! Right-aligned over its column of half-widths (pct's 6 characters)
         name = trim(adjustl(res%names(j)))
         name = adjustr(name)
         line = line//'  '//name
      end do
      line = line//'  tests'
   end function header

   function row(res, comb, value, label) result(line)
      type(design_result), intent(in) :: res
      type(design_combination), intent(in) :: comb
      real(dp), intent(in) :: value
      character(len=*), intent(in) :: label
      character(len=:), allocatable :: line
      integer :: j
      character(len=9) :: val
      ! 10/10 and more: five characters
      character(len=5) :: det
      ! Fixed widths under the header's columns
      write (val, '(f9.2)') value
      det = str(count(comb%determined))//'/'//str(size(comb%determined))
      det = adjustr(det)
      line = '    '//val//' '//det
      do j = 1, size(comb%half95)
         line = line//'  '//pct(comb%half95(j))
      end do
      line = line//'  '//label
   end function row

   !> A half-width in % in 6 characters ('>999' beyond)
   function pct(h) result(text)
      real(dp), intent(in) :: h
      character(len=6) :: text
      if (100.0_dp*h >= 999.5_dp) then
         text = '  >999'
      else if (100.0_dp*h >= 9.95_dp) then
         ! Whole per cent, without Fortran's trailing point ('14.')
         write (text, '(i6)') nint(100.0_dp*h)
      else
         write (text, '(f6.2)') 100.0_dp*h
      end if
   end function pct

   function test_list(res, k) result(text)
      type(design_result), intent(in) :: res
      integer, intent(in) :: k(:)
      character(len=:), allocatable :: text
      integer :: i
      text = ''
      do i = 1, size(k)
         if (i > 1) text = text//' + '
         text = text//trim(res%test_names(k(i)))
      end do
      if (size(k) == 0) text = '(none)'
   end function test_list

   function determined_words(res, comb) result(text)
      type(design_result), intent(in) :: res
      type(design_combination), intent(in) :: comb
      character(len=:), allocatable :: text
      integer :: j
      if (all(comb%determined)) then
         text = 'every fitted constant determined'
         return
      end if
      if (.not. any(comb%determined)) then
         text = 'determines none of'
      else
         text = 'determines'
         do j = 1, size(comb%determined)
            if (comb%determined(j)) text = text//' '//trim(res%names(j))
         end do
         text = text//'; not'
      end if
      do j = 1, size(comb%determined)
         if (.not. comb%determined(j)) text = text//' '//trim(res%names(j))
      end do
   end function determined_words
end module usharp_design
