!> Speed of the uniaxial simulators on the thesis's three tests: wall time per simulation,
!> steps, right-hand-side and Jacobian evaluations, and the error against a tight-tolerance
!> CVODE reference. RODAS4 (the default) and CVODE at their default tolerances, and RODAS4
!> at rtol 1e-7, atol 1e-10 (CVODE's default tolerances).
program bench_simulate
   use, intrinsic :: iso_fortran_env, only: int64, output_unit
   use usharp_kinds, only: dp
   use usharp_error, only: error_type
   use usharp_model_miller, only: miller_model, model_setup
   use usharp_history, only: history_type, output_times, thesis_history
   use usharp_simulation, only: solver_options, sim_result
   use usharp_cvode_driver, only: simulate_cvode
   use usharp_rosenbrock_driver, only: simulate_rosenbrock
   implicit none
   type(miller_model) :: m
   type(history_type) :: h
   type(sim_result) :: r, ref
   type(solver_options) :: opts(3), tight
   type(error_type), allocatable :: err
   real(dp), allocatable :: tout(:)
   integer(int64) :: c0, c1, rate
   integer :: k, rep, batch, v
   integer, parameter :: nrep = 500
   real(dp) :: best, t
   character(len=10), parameter :: names(3) = ['lcf       ', 'relaxation', 'ratchet   ']
   character(len=27), parameter :: setting(3) = [character(len=27) :: 'rodas4 default', &
                                                 'cvode  default', 'rodas4 rtol 1e-7 atol 1e-10']
   call model_setup(m, err)
   opts(2)%integrator = 'cvode'
   opts(3)%rtol = 1.0e-7_dp
   opts(3)%atol_strain = 1.0e-10_dp
   tight%rtol = 1.0e-11_dp
   tight%atol_strain = 1.0e-15_dp
   write (output_unit, '(a)') '# test        integrator, tolerances         ms/simulation   steps'// &
      '   rhs-evals   jac-evals   max|dsig|/peak'
   write (output_unit, '(a)') '# (default rtol, atol: rodas4 1e-5, 1e-8; cvode 1e-7, 1e-10; 0.5 s output '// &
      'interval; best of 3 batches of 500; error against CVODE at rtol 1e-11, atol 1e-15)'
   do k = 1, 3
      call thesis_history(k, h, err)
      tout = output_times(h, 0.5_dp)
      call simulate_cvode(m, h, tout, tight, ref, err)
      do v = 1, 3
         best = huge(1.0_dp)
         do batch = 1, 3
            call system_clock(c0, rate)
            do rep = 1, nrep
               call simulate(v)
            end do
            call system_clock(c1)
            t = real(c1 - c0, dp)/real(rate, dp)/nrep*1.0e3_dp
            best = min(best, t)
         end do
         write (output_unit, '(a12,a29,f12.4,3i11,es16.2)') names(k), setting(v), best, r%nsteps, &
            r%nrhs, r%njac, maxval(abs(r%stress - ref%stress))/maxval(abs(ref%stress))
      end do
   end do
contains
   subroutine simulate(v)
      integer, intent(in) :: v
      if (opts(v)%integrator == 'cvode') then
         call simulate_cvode(m, h, tout, opts(v), r, err)
      else
         call simulate_rosenbrock(m, h, tout, opts(v), r, err)
      end if
   end subroutine simulate
end program bench_simulate
