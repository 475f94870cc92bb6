!> `usharp diagnose --selfcheck`: data are generated from the model with one catalogue effect
!> injected at a realistic magnitude (drawn at random) plus Gaussian noise, the model is
!> fitted without it and diagnosed; the confusion table counts which effect came out first.
!> Clean data (noise only) must come out as "no significant effect".
module usharp_selfcheck
   use, intrinsic :: iso_fortran_env, only: int64
   use, intrinsic :: ieee_arithmetic, only: ieee_value, ieee_quiet_nan, ieee_is_nan
   use usharp_kinds, only: dp
   use usharp_error, only: error_type, fatal_error
   use usharp_strings, only: str, real_str, report_line_len
   use usharp_config, only: run_config
   use usharp_objective, only: fit_problem, setup_problem
   use usharp_experiment, only: experiment_type
   use usharp_effects, only: test_effects, effect_info, effect_catalogue, n_effects, &
                             effect_nparams
   use usharp_effect_problem, only: effect_problem, new_effect_problem
   use usharp_diagnose, only: diagnose_options, diagnose_result, diagnose_run, diagnose_report, &
                              held_quiet, rest_at_noise, named_effect, joint_decides
   use usharp_rng, only: rng_type
   use usharp_sort, only: order_of
   use usharp_task_farm, only: task_list, task_text, run_tasks
   use usharp_filesys, only: file_hash, hash_hex
   use usharp_version, only: usharp_version_string, build_id
   implicit none
   private

   public :: selfcheck_result, selfcheck_run, selfcheck_report, selfcheck_deck, inject

   !> Part of the held-out structured gap the injected effect must remove (80 %)
   real(dp), parameter :: target_shrink = 0.8_dp

   !> Outcome of the self-check
   type :: selfcheck_result
      integer, allocatable :: injected(:)      !< effects injected (0: clean), rows of the table
      integer, allocatable :: columns(:)       !< effects that can rank first (0: none), columns
      integer, allocatable :: confusion(:, :)  !< (row, 0:n_effects) ranked first (0: none)
      real(dp), allocatable :: shrink(:, :)    !< held-out gap removed by the injected effect (row, rep)
      logical, allocatable :: first(:, :)      !< the injected effect named: first, or alike with a separating test (row, rep)
      !> the injected effect's rest of the held-out gap below its floor, the part removed above it (row, rep)
      logical, allocatable :: at_noise(:, :)
      integer :: reps = 0
      real(dp) :: seconds = 0.0_dp
      integer :: nevals = 0
      integer :: failed = 0                          !< diagnoses that stopped with an error
      character(len=report_line_len), allocatable :: misses(:)  !< the reports of the wrong answers
   end type selfcheck_result

   !> The repetitions as tasks: task k is row (k - 1)/reps + 1, repetition modulo(k - 1, reps) + 1
   type, extends(task_list) :: selfcheck_tasks
      type(run_config) :: cfg
      type(diagnose_options) :: o
      real(dp) :: peak = 0.0_dp
      integer, allocatable :: rows(:)
      integer :: reps = 0
   contains
      procedure :: run => selfcheck_task
   end type selfcheck_tasks

contains

   !> Parameters of effect k (physical units, all nt tests) at a realistic magnitude drawn
   !> at random: signs at random where the effect has both; peak: the tests' peak stress
   function inject(k, nt, peak, rng) result(p)
      integer, intent(in) :: k, nt
      real(dp), intent(in) :: peak
      type(rng_type), intent(inout) :: rng
      real(dp), allocatable :: p(:)
      integer :: i
      real(dp) :: sat
      select case (k)
      case (1)
         p = [draw(0.05_dp, 0.15_dp, .false.)]        ! kappa
      case (2)
         p = [draw(0.1_dp, 0.3_dp, .false.)]          ! tau, s
      case (3)
         ! dT per test, K, alternating in sign from test to test: what all tests share is
         ! taken up by B*theta and cannot be told from a change of the constants; offsets of
         ! 3-8 K of random sign left the residual at the 1 % noise level in 6 of 10 draws
         sat = merge(1.0_dp, -1.0_dp, rng%uniform() < 0.5_dp)
         p = [(sat*(-1.0_dp)**i*draw(8.0_dp, 15.0_dp, .false.), i=1, nt)]
      case (4)
         p = [(draw(0.02_dp, 0.05_dp, .true.), i=1, nt), (draw(0.03_dp, 0.08_dp, .true.), i=1, nt)]
      case (5)
         p = [draw(0.02_dp, 0.06_dp, .true.)*peak, draw(0.02_dp, 0.05_dp, .true.)*peak]
      case (6)
         p = [draw(0.2_dp, 0.5_dp, .true.)]           ! delta, s
      case (7)
         p = [draw(0.04_dp, 0.1_dp, .false.), draw(30.0_dp, 300.0_dp, .false.)]   ! a, b
      case (8)
         sat = draw(0.05_dp, 0.12_dp, .false.)*peak
         p = [0.0_dp, draw(150.0_dp, 400.0_dp, .false.)]
         p(1) = sat*p(2)                               ! H3 = saturation * gamma3
      case (9)
         p = [(draw(2.0e-6_dp, 6.0e-6_dp, .true.), i=1, nt)]   ! drift, 1/s
      case (10)
         p = [(draw(0.02_dp, 0.05_dp, .true.), i=1, nt)]       ! gain, -
      case default
         allocate (p(0))
      end select
   contains
      real(dp) function draw(lo, hi, signed) result(v)
         real(dp), intent(in) :: lo, hi
         logical, intent(in) :: signed
         v = lo + (hi - lo)*rng%uniform()
         if (signed) then
            if (rng%uniform() < 0.5_dp) v = -v
         end if
      end function draw
   end function inject

   !> Synthetic data of cfg's tests at cfg's constants with effect k (parameters p) and
   !> Gaussian noise of sd noise*max|response| per test
   subroutine synthetic_data(cfg, k, p, noise, rng, exps, error)
      type(run_config), intent(in) :: cfg
      integer, intent(in) :: k
      real(dp), intent(in) :: p(:), noise
      type(rng_type), intent(inout) :: rng
      type(experiment_type), allocatable, intent(out) :: exps(:)
      type(error_type), allocatable, intent(out) :: error
      type(fit_problem) :: prob
      type(effect_problem) :: ep
      type(test_effects) :: base
      real(dp), allocatable :: r(:), y(:)
      integer :: i, k0, n, j
      real(dp) :: sd
      logical :: ok
      allocate (exps(size(cfg%tests)))
      do i = 1, size(cfg%tests)
         exps(i)%t = cfg%tests(i)%times()
         exps(i)%y = spread(1.0_dp, 1, size(exps(i)%t))
      end do
      call setup_problem(cfg, prob, error, exps)
      if (allocated(error)) return
      base%dlnE_dT = cfg%diagnose%dlnE_dT
      base%gamma3 = cfg%diagnose%gamma3
      call new_effect_problem(prob, [(i, i=1, size(cfg%tests))], k, base, 1.0_dp, ep, &
                              free_constants=.false., p0=p)
      ep%pfree = .false.
      allocate (r(ep%nres()), y(ep%nres()))
      call ep%residual_at(ep%start(), r, ok, y)
      if (.not. ok) then
         call fatal_error(error, cfg%path//': self-check: its tests cannot be simulated at its '// &
            '&constants '//what()//'; the data are made at the matrix''s own constants, which '// &
            'must be a material''s (a fit''s best.nml: -c), not a search''s start')
         return
      end if
      k0 = 0
      do i = 1, size(cfg%tests)
         n = size(exps(i)%t)
         exps(i)%y = y(k0 + 1:k0 + n)
         sd = noise*maxval(abs(exps(i)%y))
         do j = 1, n
            exps(i)%y(j) = exps(i)%y(j) + sd*rng%normal()
         end do
         k0 = k0 + n
      end do
   contains
      !> The data being made, for the message
      function what() result(text)
         character(len=:), allocatable :: text
         type(effect_info) :: cat(n_effects)
         if (k == 0) then
            text = 'without an effect (the clean data)'
         else
            cat = effect_catalogue(1.0_dp)
            text = 'with the injected effect '//trim(cat(k)%name)
            if (size(p) > 0) text = text//' ('//trim(cat(k)%pname(1))//' = '//real_str(p(1), 'es10.3')//')'
         end if
      end function what
   end subroutine synthetic_data

   !> Run reps repetitions for the clean data and for every considered effect; the
   !> repetitions are tasks spread over the MPI ranks and kept in journal ('' for none; mode:
   !> see run_tasks, default 'force'), so that a stopped self-check continues
   subroutine selfcheck_run(cfg, opts, sc, error, journal, mode)
      type(run_config), intent(in) :: cfg
      type(diagnose_options), intent(in) :: opts
      type(selfcheck_result), intent(out) :: sc
      type(error_type), allocatable, intent(out) :: error
      character(len=*), intent(in), optional :: journal, mode
      type(selfcheck_tasks) :: tasks
      type(task_text), allocatable :: results(:)
      type(experiment_type), allocatable :: exps(:)
      type(rng_type) :: rng
      character(len=report_line_len), allocatable :: lines(:)
      integer :: row, rep, j, c0, c1, rate, t, failed, nevals, first, named_flag, noise_flag, stat
      real(dp) :: shrink
      call system_clock(c0, rate)
      sc%reps = cfg%diagnose%reps
      sc%injected = opts%rows
      sc%columns = [0, opts%effects]
      allocate (sc%confusion(size(sc%injected), 0:n_effects), sc%shrink(size(sc%injected), sc%reps))
      sc%confusion = 0
      allocate (sc%misses(0))
      sc%shrink = 0.0_dp
      allocate (sc%first(size(sc%injected), sc%reps), sc%at_noise(size(sc%injected), sc%reps))
      sc%first = .false.
      sc%at_noise = .false.
      ! A peak for the stress-like magnitudes: that of the clean data
      call rng%seed(cfg%diagnose%seed)
      call synthetic_data(cfg, 0, [real(dp) ::], 0.0_dp, rng, exps, error)
      if (allocated(error)) return
      tasks%peak = 0.0_dp
      do j = 1, size(exps)
         tasks%peak = max(tasks%peak, maxval(abs(exps(j)%y)))
      end do
      tasks%cfg = cfg
      tasks%o = opts
      tasks%rows = sc%injected
      tasks%reps = sc%reps
      if (present(journal) .and. present(mode)) then
         call run_tasks(tasks, size(sc%injected)*sc%reps, journal, selfcheck_fingerprint(cfg), mode, &
                        results, error)
      else
         call run_tasks(tasks, size(sc%injected)*sc%reps, '', '', 'force', results, error)
      end if
      if (allocated(error)) return
      ! Every repetition's outcome read back from its text, in order
      do t = 1, size(results)
         row = (t - 1)/sc%reps + 1
         rep = modulo(t - 1, sc%reps) + 1
         call split_lines(results(t)%s, lines)
         ! (a journal of a build before the flag of the rest at noise has five fields)
         read (lines(1), *, iostat=stat) failed, nevals, first, named_flag, shrink, noise_flag
         if (stat /= 0) then
            read (lines(1), *) failed, nevals, first, named_flag, shrink
            noise_flag = 0
         end if
         sc%misses = [character(len=report_line_len) :: sc%misses, lines(2:)]
         if (failed == 1) then
            sc%failed = sc%failed + 1
            cycle
         end if
         sc%nevals = sc%nevals + nevals
         sc%confusion(row, first) = sc%confusion(row, first) + 1
         sc%first(row, rep) = named_flag == 1
         sc%shrink(row, rep) = shrink
         sc%at_noise(row, rep) = noise_flag == 1
      end do
      call system_clock(c1)
      sc%seconds = real(c1 - c0, dp)/real(rate, dp)
   end subroutine selfcheck_run

   !> One repetition (task t): the injected effect's data made, diagnosed and judged. Its text:
   !> a line 'failed nevals first named shrink at_noise', then the lines the report shows for it
   subroutine selfcheck_task(self, k, text, error)
      class(selfcheck_tasks), intent(inout) :: self
      integer, intent(in) :: k
      character(len=:), allocatable, intent(out) :: text
      type(error_type), allocatable, intent(out) :: error
      type(diagnose_result) :: res
      type(experiment_type), allocatable :: exps(:)
      type(error_type), allocatable :: e
      type(rng_type) :: rng
      real(dp), allocatable :: p(:)
      character(len=report_line_len), allocatable :: lines(:)
      character(len=80) :: head
      real(dp) :: shrink
      integer :: row, rep, ki, first, j
      logical :: named_k, at_noise
      row = (k - 1)/self%reps + 1
      rep = modulo(k - 1, self%reps) + 1
      ki = self%rows(row)
      associate (cfg => self%cfg)
         call rng%seed(cfg%diagnose%seed + 1000*ki + rep)
         call rng%skip(64)
         p = inject(ki, size(cfg%tests), self%peak, rng)
         call synthetic_data(cfg, ki, p, cfg%diagnose%noise, rng, exps, error)
         if (allocated(error)) return
         call diagnose_run(cfg, self%o, res, e, exps)
      end associate
      allocate (lines(0))
      if (allocated(e)) then
         ! A diagnosis that fails counts as a wrong answer, with its message
         lines = [character(len=report_line_len) :: '', '# failed: injected '//str(ki)// &
            ', repetition '//str(rep)//': '//e%message(1:min(len(e%message), 150))]
         write (head, '(a)') '1 0 0 0 0.0 0'
      else
         first = named_effect(res)
         named_k = named(res, ki)
         if (.not. named_k) lines = [character(len=report_line_len) :: lines, '', '---', '', &
            '# miss: injected '//str(ki)//', repetition '//str(rep)//', parameters '// &
            real_list(p), diagnose_report(res, self%o)]
         ! Held-out tests at the noise level have no gap to remove: not counted
         shrink = 0.0_dp
         if (held_quiet(res)) shrink = ieee_value(1.0_dp, ieee_quiet_nan)
         do j = 1, size(res%effects)
            if (res%effects(j)%k == ki .and. res%effects(j)%refitted .and. .not. held_quiet(res)) &
               shrink = res%effects(j)%shrink_held
         end do
         at_noise = .false.
         if (.not. held_quiet(res)) at_noise = rest_at_noise(res%gap_held, shrink, res%floor_held)
         ! A right answer that removes less than target_shrink of the held-out gap is shown too
         if (named_k .and. ki > 0 .and. shrink < target_shrink) lines = &
            [character(len=report_line_len) :: lines, '', '---', '', '# short: injected '//str(ki)// &
            ', repetition '//str(rep)//', parameters '//real_list(p)//': held-out gap removed '// &
            real_str(100.0_dp*shrink, 'f0.1')//' %', diagnose_report(res, self%o)]
         write (head, '(a,1x,i0,1x,i0,1x,i1,1x,es25.17e3,1x,i1)') '0', res%nevals, first, &
            merge(1, 0, named_k), shrink, merge(1, 0, at_noise)
      end if
      text = trim(head)//new_line('a')
      do j = 1, size(lines)
         text = text//trim(lines(j))//new_line('a')
      end do
   end subroutine selfcheck_task

   !> What decides a self-check's results: the program version and the deck's contents
   function selfcheck_fingerprint(cfg) result(fp)
      type(run_config), intent(in) :: cfg
      character(len=:), allocatable :: fp
      integer(int64) :: h
      logical :: ok
      call file_hash(cfg%path, h, ok)
      fp = 'version='//usharp_version_string//' build='//build_id()//' input='//hash_hex(h)
   end function selfcheck_fingerprint

   !> The lines of a text whose lines end with new_line('a')
   subroutine split_lines(text, lines)
      character(len=*), intent(in) :: text
      character(len=report_line_len), allocatable, intent(out) :: lines(:)
      integer :: at, nl, n
      n = 0
      do at = 1, len(text)
         if (text(at:at) == new_line('a')) n = n + 1
      end do
      allocate (lines(n))
      at = 1
      do n = 1, size(lines)
         nl = index(text(at:), new_line('a'))
         lines(n) = text(at:at + nl - 2)
         at = at + nl
      end do
   end subroutine split_lines

   !> The confusion table (rows: injected, columns: ranked first) in Markdown
   function selfcheck_report(sc) result(lines)
      type(selfcheck_result), intent(in) :: sc
      character(len=report_line_len), allocatable :: lines(:)
      type(effect_info) :: cat(n_effects)
      character(len=report_line_len) :: ln
      integer :: row, j
      cat = effect_catalogue(1.0_dp)
      allocate (lines(0))
      lines = [character(len=report_line_len) :: lines, '# usharp diagnose --selfcheck', '', &
               str(sc%reps)//' repetitions per row, effects injected at random realistic '// &
               'magnitudes with noise; rows: injected, columns: ranked first', '']
      ln = '| injected |'
      do j = 1, size(sc%columns)
         ln = trim(ln)//' '//trim(name_of(sc%columns(j)))//' |'
      end do
      lines = [lines, ln]
      ln = '|---|'
      do j = 1, size(sc%columns)
         ln = trim(ln)//'---|'
      end do
      lines = [lines, ln]
      do row = 1, size(sc%injected)
         ln = '| '//trim(name_of(sc%injected(row)))//' |'
         do j = 1, size(sc%columns)
            ln = trim(ln)//' '//str(sc%confusion(row, sc%columns(j)))//' |'
         end do
         lines = [lines, ln]
      end do
      lines = [character(len=report_line_len) :: lines, '', 'Held-out structured gap removed by the injected '// &
               'effect (min / median over repetitions):', '']
      do row = 1, size(sc%injected)
         if (sc%injected(row) == 0) cycle
         associate (v => pack(sc%shrink(row, :), .not. ieee_is_nan(sc%shrink(row, :))))
            if (size(v) == 0) then
               lines = [character(len=report_line_len) :: lines, '- '//trim(name_of(sc%injected(row)))// &
                        ': no repetition had a held-out gap']
            else
               ln = '- '//trim(name_of(sc%injected(row)))//': '//real_str(100.0_dp*minval(v), 'f0.1')// &
                    ' % / '//real_str(100.0_dp*median_of(v), 'f0.1')//' %; at least '// &
                    str(nint(100.0_dp*target_shrink))//' % in '// &
                    str(count(v >= target_shrink))//' of '//str(size(v))//' ('// &
                    str(count(sc%shrink(row, :) >= target_shrink .and. sc%first(row, :)))//' of the '// &
                    str(count(sc%first(row, :) .and. .not. ieee_is_nan(sc%shrink(row, :))))// &
                    ' named); at least '//str(nint(100.0_dp*target_shrink))//' % or the rest '// &
                    'below its floor in '//str(count(sc%shrink(row, :) >= target_shrink .or. &
                    sc%at_noise(row, :)))//' of '//str(size(v))
               if (size(v) < sc%reps) ln = trim(ln)//' ('//str(sc%reps - size(v))// &
                  ' repetitions without a held-out gap)'
               lines = [character(len=report_line_len) :: lines, ln]
            end if
         end associate
      end do
      ! (two lines: one was cut at the lines' length, the simulations' count with it)
      lines = [character(len=report_line_len) :: lines, '', 'correct (the injected effect ranked first, or '// &
               'named as explaining the gap equally well with a separating test proposed; '// &
               'clean data: no effect confirmed): '//str(correct())//' of '// &
               str(size(sc%injected)*sc%reps)//' ('//str(sc%failed)//' failed, not in the table);', &
               str(sc%nevals)//' simulations of the test set in '//real_str(sc%seconds, 'f0.1')//' s']
      if (size(sc%misses) > 0) lines = [character(len=report_line_len) :: lines, '', &
         'The reports of the wrong answers (and of right ones that remove less than '// &
         str(nint(100.0_dp*target_shrink))//' % of the '// &
         'held-out gap) follow.', sc%misses]
   contains
      function name_of(k) result(text)
         integer, intent(in) :: k
         character(len=:), allocatable :: text
         if (k == 0) then
            text = 'none'
         else
            text = trim(cat(k)%name)
         end if
      end function name_of
      integer function correct() result(n)
         n = count(sc%first)
      end function correct
   end function selfcheck_report

   !> Whether a diagnosis names the injected effect k: ranked first, or among the effects
   !> that explain the gap equally well with a test that would separate them proposed
   !> (k = 0, clean data: no effect confirmed)
   pure logical function named(res, k)
      type(diagnose_result), intent(in) :: res
      integer, intent(in) :: k
      if (joint_decides(res)) then
         named = named_by(res%joint, k)
      else
         named = named_by(res, k)
      end if
   end function named

   !> named, for one diagnosis (without its joint stage)
   pure logical function named_by(res, k) result(named)
      type(diagnose_result), intent(in) :: res
      integer, intent(in) :: k
      integer :: j
      named = .false.
      if (res%leading > 0) named = res%effects(res%leading)%k == k
      if (k == 0) then
         named = res%leading == 0
         return
      end if
      if (named .or. .not. allocated(res%alike) .or. .not. allocated(res%seps)) return
      if (size(res%seps) == 0) return
      do j = 1, size(res%alike)
         if (res%alike(j) > 0 .and. res%alike(j) <= size(res%effects)) then
            if (res%effects(res%alike(j))%k == k) named = .true.
         end if
      end do
   end function named_by

   pure function real_list(p) result(text)
      real(dp), intent(in) :: p(:)
      character(len=:), allocatable :: text
      integer :: j
      text = ''
      do j = 1, size(p)
         text = text//' '//real_str(p(j), 'es10.3')
      end do
   end function real_list

   pure real(dp) function median_of(a) result(m)
      real(dp), intent(in) :: a(:)
      integer :: order(size(a))
      order = order_of(a)
      m = a(order((size(a) + 1)/2))
   end function median_of

   !> The built-in self-check matrix (Type 304 at 593 C, Table 4): three fit tests and two
   !> held out, 1 % noise. The held-out hold test is there for the temperature effect: slow
   !> cycling alone hardly feels 8-15 K (its gap stayed under its floor in 10 of 10)
   function selfcheck_deck() result(lines)
      character(len=120), allocatable :: lines(:)
      lines = [character(len=120) :: &
         '! usharp diagnose --selfcheck: the matrix on which every catalogue effect is injected', &
         '! (Table 4 constants, Type 304 stainless steel at 593 C, stresses in ksi)', &
         '&model', "  name = 'miller', units = 'ksi', temperature = 866.15, tm = 1800.0, youngs = 22.5e3", &
         '/', '&constants', &
         '  a1 = 0.8, a2 = 7.42e-5, b = 1.0e15, c2 = 0.1, h1 = 280.0, h2 = 100.0, n = 5.8, q = 91000.0', &
         '/', '&fit', "  fitted = 'A1', 'A2', 'B', 'C2', 'H1', 'H2', 'n'", "  method = 'lm', objective = 'eq7'", &
         '/', '&diagnose', "  holdout = 'cyc1.5-slow', 'cyc1.5-hold'", '  reps = 10, seed = 1, noise = 0.01, n_refit = 4', '/', &
         '&output', "  out_dir = 'selfcheck'", '/', &
         "&test   ! 1 % range at 1e-3/s, 20 cycles", &
         "  name = 'cyc1', history = 'cyclic', dt_out = 0.2", &
         '  strain_range = 0.01, strain_rate = 1.0e-3, cycles = 20', '/', &
         "&test   ! 2 % range at 1e-3/s, 3 cycles, 5-minute hold at peak tension", &
         "  name = 'cyc2-hold', history = 'cyclic', dt_out = 0.2", &
         '  strain_range = 0.02, strain_rate = 1.0e-3, cycles = 3, hold_max = 300.0', '/', &
         "&test   ! relaxation at 0.5 % and 1 %, 10 minutes each", &
         "  name = 'relax', history = 'relaxation', dt_out = 0.5", &
         '  levels = 0.005, 0.01, ramp_time = 5.0, holds = 600.0, 600.0', '/', &
         "&test   ! held out: 1.5 % range at 1e-4/s, 2 cycles", &
         "  name = 'cyc1.5-slow', history = 'cyclic', dt_out = 1.0", &
         '  strain_range = 0.015, strain_rate = 1.0e-4, cycles = 2', '/', &
         "&test   ! held out: 1.5 % range at 1e-3/s, 2 cycles, 2-minute hold at peak tension", &
         "  name = 'cyc1.5-hold', history = 'cyclic', dt_out = 0.5", &
         '  strain_range = 0.015, strain_rate = 1.0e-3, cycles = 2, hold_max = 120.0', '/']
   end function selfcheck_deck
end module usharp_selfcheck
