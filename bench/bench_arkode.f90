!> RODAS4 against ARKODE (ARKStep, ESDIRK ARK4(3)6L[2]SA, analytic Jacobian) on the tests of
!> a deck: per test set, the wall time of simulating every test (ms, best of 5) and the largest
!> |stress - reference| / peak stress, the reference RODAS4 at rtol 1e-10, atol 1e-14, for
!> several relative tolerances (atol: the integrator's default strain tolerance).
!> Usage: bench_arkode DECK.nml [DECK.nml ...]
program bench_arkode
   use, intrinsic :: iso_fortran_env, only: int64, output_unit, error_unit
   use usharp_kinds, only: dp
   use usharp_error, only: error_type
   use usharp_history, only: output_times
   use usharp_simulation, only: sim_result, solver_options
   use usharp_rosenbrock_driver, only: simulate_rosenbrock
   use usharp_arkode_driver, only: simulate_arkode
   use usharp_config, only: run_config
   use usharp_input, only: read_config_as
   implicit none
   type(run_config) :: cfg
   type(error_type), allocatable :: err
   character(len=512) :: path
   type(sim_result), allocatable :: ref(:)
   real(dp), parameter :: rtols(4) = [1.0e-4_dp, 1.0e-5_dp, 2.0e-6_dp, 1.0e-6_dp]
   integer :: a, i, v, r
   logical, parameter :: debug = .false.
   do a = 1, command_argument_count()
      call get_command_argument(a, path)
      call read_config_as(trim(path), '', '', cfg, err)
      if (allocated(err)) then
         write (error_unit, '(a)') err%message
         stop 1
      end if
      allocate (ref(size(cfg%tests)))
      do i = 1, size(cfg%tests)
         call run(1, i, 1.0e-10_dp, 1.0e-14_dp, ref(i))
      end do
      write (output_unit, '(a,i0,a)') '# '//trim(path)//' (', size(cfg%tests), &
         ' tests): integrator, rtol, ms for all tests, steps, max|dstress|/peak'
      do v = 1, 2
         do r = 1, size(rtols)
            call report(v, rtols(r))
         end do
      end do
      deallocate (ref)
   end do
contains
   subroutine run(v, i, rtol, atol, res)
      integer, intent(in) :: v, i
      real(dp), intent(in) :: rtol, atol
      type(sim_result), intent(out) :: res
      type(solver_options) :: opts
      opts = cfg%solver
      opts%rtol = rtol
      opts%atol_strain = atol
      if (v == 1) then
         call simulate_rosenbrock(cfg%model, cfg%tests(i)%hist, &
            output_times(cfg%tests(i)%hist, cfg%tests(i)%dt_out), opts, res, err)
      else
         call simulate_arkode(cfg%model, cfg%tests(i)%hist, &
            output_times(cfg%tests(i)%hist, cfg%tests(i)%dt_out), opts, res, err)
      end if
      if (allocated(err)) then
         write (error_unit, '(a)') err%message
         stop 3
      end if
   end subroutine run

   subroutine report(v, rtol)
      integer, intent(in) :: v
      real(dp), intent(in) :: rtol
      character(len=6), parameter :: names(2) = ['rodas4', 'arkode']
      type(sim_result) :: res
      integer(int64) :: c0, c1, rate
      real(dp) :: best, worst
      integer :: b, i, steps
      best = huge(1.0_dp)
      do b = 1, 5
         call system_clock(c0, rate)
         do i = 1, size(cfg%tests)
            call run(v, i, rtol, 1.0e-8_dp, res)
         end do
         call system_clock(c1)
         best = min(best, real(c1 - c0, dp)/real(rate, dp)*1.0e3_dp)
      end do
      worst = 0.0_dp
      steps = 0
      do i = 1, size(cfg%tests)
         call run(v, i, rtol, 1.0e-8_dp, res)
         steps = steps + int(res%nsteps)
         worst = max(worst, maxval(abs(res%stress - ref(i)%stress))/maxval(abs(ref(i)%stress)))
         if (debug) write (output_unit, '(4x,a20,es12.2,f12.3,i6)') cfg%tests(i)%name, &
            maxval(abs(res%stress - ref(i)%stress))/maxval(abs(ref(i)%stress)), &
            res%t(maxloc(abs(res%stress - ref(i)%stress), 1)), int(res%nsteps)
      end do
      write (output_unit, '(a8,es10.1,f12.3,i9,es12.2)') names(v), rtol, best, steps, worst
   end subroutine report
end program bench_arkode
