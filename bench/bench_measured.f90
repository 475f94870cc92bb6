!> Cost and accuracy of simulating under a measured strain: one objective evaluation of a
!> measured-strain fit deck against one of the thesis deck, measured in the same run, with
!> the measured strain as smooth forcing (the default) and as the piecewise-linear history
!> through every sample (the integrator stops at each); the stress of both against a
!> tight-tolerance reference under the same forcing, at the given constants and at the
!> measured deck's own (start) constants; the objective of both; the diagnosis's model with
!> effects at zero against the plain model, with the extended states p and R2 carried at
!> rest and without (as the diagnosis leaves them where no effect acts through them). Writes each
!> test's simulated loops of both treatments to OUT/<test>.forcing.txt for the plots.
!> Usage: bench_measured THESIS.nml MEASURED.nml CONSTANTS.nml OUT, or bench_measured
!> DECK.nml [CONSTANTS.nml] for one deck's time per evaluation alone (at the deck's constants,
!> or at those of CONSTANTS.nml).
program bench_measured
   use, intrinsic :: iso_fortran_env, only: int64, output_unit, error_unit
   use usharp_kinds, only: dp
   use usharp_error, only: error_type
   use usharp_history, only: history_type, history_from_points, control_strain
   use usharp_forcing, only: measured_history
   use usharp_simulation, only: sim_result, solver_options
   use usharp_simulate, only: simulate_test
   use usharp_config, only: run_config
   use usharp_input, only: read_config_as, read_data_columns
   use usharp_table, only: merge_repeated_times
   use usharp_objective, only: fit_problem, setup_problem
   use usharp_effect_values, only: test_effects
   use usharp_effect_problem, only: simulate_effect
   implicit none
   type(run_config) :: thesis, smooth, raw, start
   type(fit_problem) :: p_thesis, p_smooth, p_raw
   type(error_type), allocatable :: err
   character(len=512) :: arg(4)
   real(dp) :: t_thesis, t_smooth, t_raw, f_smooth, f_raw
   real(dp), allocatable :: per_smooth(:), per_raw(:)
   integer :: i, nt
   integer(int64) :: work(3)

   do i = 1, 4
      call get_command_argument(i, arg(i))
   end do
   if (command_argument_count() <= 2) then
      call read_config_as(trim(arg(1)), trim(arg(2)), '', thesis, err)
      call check()
      call setup_problem(thesis, p_thesis, err)
      call check()
      t_thesis = huge(1.0_dp)
      do i = 1, 5
         t_thesis = min(t_thesis, time_eval(p_thesis, 50))
      end do
      write (output_unit, '(a,i0,a,f9.4)') trim(arg(1))//' (', size(thesis%tests), &
         ' tests): ms per evaluation ', t_thesis
      call deck_work(thesis, work(1), work(2), work(3))
      write (output_unit, '(a,i0,a,i0)') 'steps ', work(1), ', rate evaluations ', work(2)
      stop
   end if
   if (len_trim(arg(4)) == 0) then
      write (error_unit, '(a)') 'usage: bench_measured THESIS.nml MEASURED.nml CONSTANTS.nml OUT'
      stop 2
   end if
   call read_config_as(trim(arg(1)), '', '', thesis, err)
   call check()
   call read_config_as(trim(arg(2)), trim(arg(3)), '', smooth, err)
   call check()
   raw = smooth
   nt = size(smooth%tests)
   do i = 1, nt
      call raw_history(i)
   end do
   call setup_problem(thesis, p_thesis, err)
   call check()
   call setup_problem(smooth, p_smooth, err)
   call check()
   call setup_problem(raw, p_raw, err)
   call check()
   allocate (per_smooth(nt), per_raw(nt))

   ! Interleaved batches, best of each: the load of a shared machine falls on all three alike
   t_thesis = huge(1.0_dp)
   t_smooth = huge(1.0_dp)
   t_raw = huge(1.0_dp)
   do i = 1, 5
      t_thesis = min(t_thesis, time_eval(p_thesis, 20))
      t_smooth = min(t_smooth, time_eval(p_smooth, 10, f_smooth, per_smooth))
      t_raw = min(t_raw, time_eval(p_raw, 2, f_raw, per_raw))
   end do
   write (output_unit, '(a)') '# one objective evaluation (ms, best of 5 batches, interleaved)'
   write (output_unit, '(a,i0,a,f9.3)') 'thesis (', size(thesis%tests), ' tests)            ', &
      t_thesis
   write (output_unit, '(a,i0,a,f9.3,a,f6.2)') 'measured, smooth forcing (', nt, ')   ', &
      t_smooth, '   ratio to thesis ', t_smooth/t_thesis
   write (output_unit, '(a,i0,a,f9.3,a,f6.2)') 'measured, every sample (', nt, ')     ', &
      t_raw, '   ratio to thesis ', t_raw/t_thesis
   write (output_unit, '(a,2f12.4)') 'objective (Eq. 8) smooth, every sample: ', f_smooth, f_raw
   call per_step()
   write (output_unit, '(a)') '# test: knots of the smooth forcing; steps smooth / every sample; '// &
      'max|stress - tight reference|/peak smooth, every sample; max|smooth - every sample|/peak; objective smooth, every sample'
   do i = 1, nt
      call compare(i)
   end do
   call at_rest()
   ! The deck's own constants (a fit's start, far from these data): a harder case for the
   ! error control, the stress there being a small difference of large strains
   call read_config_as(trim(arg(2)), '', '', start, err)
   call check()
   write (output_unit, '(a)') '# at the deck''s start constants, smooth forcing: test, steps, '// &
      'max|stress - tight reference|/peak'
   do i = 1, nt
      call start_accuracy(i)
   end do

contains

   subroutine check()
      if (allocated(err)) then
         write (error_unit, '(a)') err%message
         stop 1
      end if
   end subroutine check

   !> The history through every sample of test i's measured strain, as before smoothing
   subroutine raw_history(i)
      integer, intent(in) :: i
      real(dp), allocatable :: vals(:, :)
      character(len=128) :: cols(2)
      integer :: nmerged
      cols(1) = raw%tests(i)%data%time_col
      cols(2) = raw%tests(i)%data%strain_col
      call read_data_columns(raw%tests(i)%data, cols, vals, err)
      call check()
      call merge_repeated_times(vals, raw%tests(i)%data%file, nmerged, err)
      call check()
      call history_from_points(vals(:, 1), vals(:, 2), control_strain, raw%tests(i)%hist, err)
      call check()
   end subroutine raw_history

   !> Mean wall time (ms) of one objective evaluation at the deck's constants over n
   real(dp) function time_eval(p, n, total, per_test) result(ms)
      type(fit_problem), intent(in) :: p
      integer, intent(in) :: n
      real(dp), intent(out), optional :: total, per_test(:)
      real(dp) :: x(size(p%idx)), f, per(size(p%targets))
      integer(int64) :: c0, c1, rate
      integer :: k, status
      character(len=:), allocatable :: message
      x = p%start_point()
      call system_clock(c0, rate)
      do k = 1, n
         call p%evaluate(x, f, per, status, message)
      end do
      call system_clock(c1)
      if (status /= 0) then
         write (error_unit, '(a)') 'evaluation failed: '//message
         stop 3
      end if
      ms = real(c1 - c0, dp)/real(rate, dp)/real(n, dp)*1.0e3_dp
      if (present(total)) total = f
      if (present(per_test)) per_test = per
   end function time_eval

   !> Steps, rate evaluations and output points of one evaluation of the thesis deck and of
   !> the measured deck (smooth forcing), and the time per step of each: the ratio of the
   !> evaluations' times is, step for step, that of their rate evaluations
   subroutine per_step()
      integer(int64) :: steps(2), outs(2), nrhs(2)
      call deck_work(thesis, steps(1), nrhs(1), outs(1))
      call deck_work(smooth, steps(2), nrhs(2), outs(2))
      write (output_unit, '(a)') '# steps, rate evaluations, output points and microseconds per '// &
         'step of one evaluation'
      write (output_unit, '(a,3i8,f9.3)') 'thesis                  ', steps(1), nrhs(1), outs(1), &
         1.0e3_dp*t_thesis/real(steps(1), dp)
      write (output_unit, '(a,3i8,f9.3)') 'measured, smooth forcing', steps(2), nrhs(2), outs(2), &
         1.0e3_dp*t_smooth/real(steps(2), dp)
   end subroutine per_step

   !> Steps, rate evaluations and output points of one evaluation of a deck's tests at its
   !> constants
   subroutine deck_work(cfg, steps, nrhs, outs)
      type(run_config), intent(in) :: cfg
      integer(int64), intent(out) :: steps, nrhs, outs
      type(sim_result) :: r
      integer :: k
      steps = 0
      nrhs = 0
      outs = 0
      do k = 1, size(cfg%tests)
         call simulate_test(cfg%model, cfg%solver, cfg%tests(k), r, err)
         call check()
         steps = steps + r%nsteps
         nrhs = nrhs + r%nrhs
         outs = outs + size(r%t)
      end do
   end subroutine deck_work

   !> Test i: both treatments against their tight references, and the loops to a file
   subroutine compare(i)
      integer, intent(in) :: i
      type(solver_options) :: tight
      type(sim_result) :: rs, rr, ts, tr
      real(dp) :: peak
      integer :: u, k
      tight = smooth%solver
      tight%rtol = 1.0e-10_dp
      tight%atol_strain = 1.0e-14_dp
      call simulate_test(smooth%model, smooth%solver, smooth%tests(i), rs, err)
      call check()
      call simulate_test(smooth%model, tight, smooth%tests(i), ts, err)
      call check()
      call simulate_test(raw%model, raw%solver, raw%tests(i), rr, err)
      call check()
      call simulate_test(raw%model, tight, raw%tests(i), tr, err)
      call check()
      peak = maxval(abs(ts%stress))
      write (output_unit, '(a20,2i7,i7,3es11.2,2f10.3)') smooth%tests(i)%name, &
         size(smooth%tests(i)%hist%tk), rs%nsteps, rr%nsteps, &
         maxval(abs(rs%stress - ts%stress))/peak, maxval(abs(rr%stress - tr%stress))/peak, &
         maxval(abs(rs%stress - rr%stress))/peak, per_smooth(i), per_raw(i)
      open (newunit=u, file=trim(arg(4))//'/'//smooth%tests(i)%name//'.forcing.txt', &
            status='replace', action='write')
      write (u, '(a)') '# time (s), measured strain, smoothed strain (-), measured stress, '// &
         'simulated stress every sample, smooth forcing, its tight reference (MPa)'
      do k = 1, size(rs%t)
         write (u, '(f10.3,2es14.6,4f10.3)') rs%t(k), rr%strain(k), rs%strain(k), &
            p_smooth%targets(i)%y_ex(k), rr%stress(k), rs%stress(k), ts%stress(k)
      end do
      close (u)
   end subroutine compare
   !> The seven tests simulated by the model with effects at zero, p and R2 carried at rest
   !> and not, against the plain model (ms per simulation of all, best of 5 interleaved
   !> batches; the stress without them is the plain model's bit for bit)
   subroutine at_rest()
      type(sim_result) :: r(3)
      real(dp) :: t(3), dmax
      integer(int64) :: c0, c1, rate
      integer :: b, k, j, v
      logical :: same
      t = huge(1.0_dp)
      do b = 1, 5
         do v = 1, 3
            call system_clock(c0, rate)
            do k = 1, 10
               do j = 1, nt
                  call at_zero(v, j, r(v))
               end do
            end do
            call system_clock(c1)
            t(v) = min(t(v), real(c1 - c0, dp)/real(rate, dp)*1.0e2_dp)
         end do
      end do
      same = .true.
      dmax = 0.0_dp
      do j = 1, nt
         do v = 1, 3
            call at_zero(v, j, r(v))
         end do
         same = same .and. all(r(2)%stress == r(1)%stress)
         dmax = max(dmax, maxval(abs(r(3)%stress - r(1)%stress))/maxval(abs(r(1)%stress)))
      end do
      write (output_unit, '(a)') '# effects at zero (the diagnosis''s model), ms per simulation of the tests'
      write (output_unit, '(a,f9.3)') 'plain model                          ', t(1)
      write (output_unit, '(a,f9.3,a,l1)') 'effects, p and R2 not carried       ', t(2), &
         '   stress the plain model''s bit for bit: ', same
      write (output_unit, '(a,f9.3,a,f6.3,a,es9.2)') 'effects, p and R2 carried at rest   ', t(3), &
         '   ratio to not carried ', t(3)/t(2), '   max|stress - plain|/peak ', dmax
   end subroutine at_rest

   !> Test j simulated by the plain model (v = 1) or the model with effects at zero, p and R2
   !> not carried (2) or carried (3)
   subroutine at_zero(v, j, res)
      integer, intent(in) :: v, j
      type(sim_result), intent(out) :: res
      type(test_effects) :: zero
      if (v == 1) then
         call simulate_test(smooth%model, smooth%solver, smooth%tests(j), res, err)
      else
         call simulate_effect(smooth%model, zero, smooth%tests(j)%hist, p_smooth%targets(j)%t, &
                              smooth%solver, res, err, smooth%tests(j)%temperature, states=v == 3)
      end if
      call check()
   end subroutine at_zero

   !> Test i at the start constants: smooth forcing against its tight reference
   subroutine start_accuracy(i)
      integer, intent(in) :: i
      type(solver_options) :: tight
      type(sim_result) :: rs, ts
      tight = start%solver
      tight%rtol = 1.0e-10_dp
      tight%atol_strain = 1.0e-14_dp
      call simulate_test(start%model, start%solver, start%tests(i), rs, err)
      call check()
      call simulate_test(start%model, tight, start%tests(i), ts, err)
      call check()
      write (output_unit, '(a20,i7,es11.2)') start%tests(i)%name, rs%nsteps, &
         maxval(abs(rs%stress - ts%stress))/maxval(abs(ts%stress))
   end subroutine start_accuracy
end program bench_measured
