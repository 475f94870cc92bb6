!> Speed of the implicit stress update and of the umat path on the thesis's three tests at the
!> default increments (initial 0.1 s, minimum 1e-8 s, maximum 0.15 s)
program bench_umat
   use, intrinsic :: iso_fortran_env, only: int64, output_unit
   use usharp_kinds, only: dp
   use usharp_error, only: error_type
   use usharp_model_miller, only: miller_model, model_setup
   use usharp_model_miller, only: n_state
   use usharp_history, only: history_type, output_times, thesis_history
   use usharp_simulation, only: solver_options, sim_result
   use usharp_umat_driver, only: simulate_umat
   implicit none
   type(miller_model) :: m
   type(history_type) :: h
   type(sim_result) :: r
   type(solver_options) :: opts
   type(error_type), allocatable :: err
   integer(int64) :: c0, c1, rate
   real(dp) :: y0(n_state), y(n_state), sig(6), c(6, 6), ein(6), t
   integer :: k, rep, st, nsub
   integer, parameter :: ncalls = 20000
   character(len=10), parameter :: names(3) = ['lcf       ', 'relaxation', 'ratchet   ']
   call model_setup(m, err)
   ! One update call across the knee (inelastic, 0.15 s, default substeps)
   ein = 0.003_dp*[1.0_dp, -0.5_dp, -0.5_dp, 0.0_dp, 0.0_dp, 0.0_dp]
   y0 = [ein, 8.0_dp*[2.0_dp/3, -1.0_dp/3, -1.0_dp/3, 0.0_dp, 0.0_dp, 0.0_dp], 11.5_dp]
   call system_clock(c0, rate)
   do rep = 1, ncalls
      call m%stress_update(ein + [8.0e-4_dp, -2.4e-4_dp, -2.4e-4_dp, 0.0_dp, 0.0_dp, 0.0_dp], &
                           [2.0e-5_dp, -9.0e-6_dp, -9.0e-6_dp, 0.0_dp, 0.0_dp, 0.0_dp], 0.15_dp, y0, sig, &
                           y, c, st, nsub)
   end do
   call system_clock(c1)
   t = real(c1 - c0, dp)/real(rate, dp)
   write (output_unit, '(a,f12.0,a,i0,a)') 'stress-update calls per second (inelastic, 0.15 s): ', &
      ncalls/t, ' (', nsub, ' backward-Euler substeps each)'
   write (output_unit, '(a)') '# test        ms/simulation  increments  update calls'
   do k = 1, 3
      call thesis_history(k, h, err)
      call system_clock(c0)
      do rep = 1, 3
         call simulate_umat(m, h, output_times(h, 1.0_dp), opts, r, err)
      end do
      call system_clock(c1)
      write (output_unit, '(a12,f14.2,2i12)') names(k), real(c1 - c0, dp)/real(rate, dp)/3*1.0e3_dp, &
         r%nsteps, r%nrhs
   end do
end program bench_umat
