!> Speed of the uniaxial simulator on the thesis's three tests at default tolerances:
!> wall time per simulation, steps and right-hand-side evaluations
program bench_simulate
   use, intrinsic :: iso_fortran_env, only: int64, output_unit
   use usharp_kinds, only: dp
   use usharp_error, only: error_type
   use usharp_miller, only: miller_model, model_setup
   use usharp_history, only: history_type, output_times, thesis_history
   use usharp_simulation, only: solver_options, sim_result
   use usharp_cvode_driver, only: simulate_cvode
   implicit none
   type(miller_model) :: m
   type(history_type) :: h
   type(sim_result) :: r
   type(solver_options) :: opts
   type(error_type), allocatable :: err
   real(dp), allocatable :: tout(:)
   integer(int64) :: c0, c1, rate
   integer :: k, rep
   integer, parameter :: nrep = 500
   character(len=10), parameter :: names(3) = ['lcf       ', 'relaxation', 'ratchet   ']
   call model_setup(m, err)
   write (output_unit, '(a)') '# test        ms/simulation   steps   rhs-evals   jac-evals   max|dsig|/peak'
   write (output_unit, '(a)') '# (default rtol, atol; 0.5 s output interval; best of 3 batches of 500; '// &
      'error against rtol 1e-11, atol 1e-15)'
   do k = 1, 3
      call thesis_history(k, h, err)
      tout = output_times(h, 0.5_dp)
      block
         real(dp) :: best, t
         integer :: batch
         best = huge(1.0_dp)
         do batch = 1, 3
            call system_clock(c0, rate)
            do rep = 1, nrep
               call simulate_cvode(m, h, tout, opts, r, err)
            end do
            call system_clock(c1)
            t = real(c1 - c0, dp)/real(rate, dp)/nrep*1.0e3_dp
            best = min(best, t)
         end do
         block
            type(sim_result) :: ref
            type(solver_options) :: tight
            tight%rtol = 1.0e-11_dp
            tight%atol_strain = 1.0e-15_dp
            call simulate_cvode(m, h, tout, tight, ref, err)
            write (output_unit, '(a12,f14.4,3i11,es16.2)') names(k), best, r%nsteps, r%nrhs, r%njac, &
               maxval(abs(r%stress - ref%stress))/maxval(abs(ref%stress))
         end block
      end block
   end do
end program bench_simulate
