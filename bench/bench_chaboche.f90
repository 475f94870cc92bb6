!> Uniaxial response of the Chaboche model to four strain histories (tension at two rates, a
!> fully reversed cycle, a ramp and hold), integrated tightly (classical RK4, 2000 steps per
!> output interval) for bench/chaboche_neml.py, which drives NEML through the same points.
!> Output: a '# constants' line (names, then values, E and Poisson's ratio last), then per
!> history a '# history NAME' line and rows 'time strain stress'.
program bench_chaboche
   use, intrinsic :: iso_fortran_env, only: output_unit
   use usharp_kinds, only: dp
   use usharp_error, only: error_type
   use usharp_model_chaboche, only: chaboche_model, chaboche_setup, chaboche_uniaxial_rates, &
      chaboche_n_uniaxial, chaboche_n_constants, chaboche_constant_names, chaboche_get_constant, &
      chaboche_set_constant
   implicit none
   type(chaboche_model) :: m
   type(error_type), allocatable :: error
   integer :: i
   real(dp) :: v
   character(len=32) :: arg

   ! Constants of the size found for Alloy 617 near 950 C (the model tests' set); a list of
   ! 13 values on the command line replaces them
   m%youngs = 144000.0_dp
   m%poisson = 0.3_dp
   m%c%s0 = 10.0_dp
   m%c%eta = 500.0_dp
   m%c%n = 5.0_dp
   m%c%q = 30.0_dp
   m%c%b = 20.0_dp
   m%c%c = [8.0e4_dp, 5.0e3_dp]
   m%c%g = [1500.0_dp, 60.0_dp]
   m%c%a = [1.0e-7_dp, 1.0e-6_dp]
   m%c%m = [2.0_dp, 3.0_dp]
   if (command_argument_count() >= chaboche_n_constants) then
      do i = 1, chaboche_n_constants
         call get_command_argument(i, arg)
         read (arg, *) v
         call chaboche_set_constant(m%c, i, v)
      end do
   end if
   call chaboche_setup(m, error)
   if (allocated(error)) error stop 'inadmissible constants'
   write (output_unit, '(a,*(1x,a))') '# constants', (trim(chaboche_constant_names(i)), &
      i=1, chaboche_n_constants), 'E', 'nu'
   write (output_unit, '(a,*(1x,es23.15))') '# values', (chaboche_get_constant(m%c, i), &
      i=1, chaboche_n_constants), m%youngs, m%poisson
   call run('tension-1e-3', [0.0_dp, 20.0_dp], [0.0_dp, 0.02_dp], 100)
   call run('tension-1e-4', [0.0_dp, 200.0_dp], [0.0_dp, 0.02_dp], 100)
   call run('cycle-0.6pct-1e-3', [0.0_dp, 6.0_dp, 18.0_dp, 30.0_dp, 42.0_dp, 48.0_dp], &
            [0.0_dp, 0.006_dp, -0.006_dp, 0.006_dp, -0.006_dp, 0.0_dp], 40)
   call run('ramp-1pct-hold-600s', [0.0_dp, 10.0_dp, 610.0_dp], [0.0_dp, 0.01_dp, 0.01_dp], 60)

contains

   !> Piecewise-linear strain through (tk, ek), nout output intervals per segment
   subroutine run(name, tk, ek, nout)
      character(len=*), intent(in) :: name
      real(dp), intent(in) :: tk(:), ek(:)
      integer, intent(in) :: nout
      integer, parameter :: nsub = 2000, nu = chaboche_n_uniaxial
      real(dp) :: y(nu), k1(nu), k2(nu), k3(nu), k4(nu), h, t, rate, e
      integer :: seg, io, is
      write (output_unit, '(a)') '# history '//name
      y = 0.0_dp
      write (output_unit, '(3es24.15)') tk(1), ek(1), 0.0_dp
      do seg = 1, size(tk) - 1
         rate = (ek(seg + 1) - ek(seg))/(tk(seg + 1) - tk(seg))
         h = (tk(seg + 1) - tk(seg))/(nout*nsub)
         do io = 1, nout
            do is = 1, nsub
               t = ((io - 1)*nsub + is - 1)*h
               e = ek(seg) + rate*t
               call rates(e, y, k1)
               call rates(e + rate*h/2, y + h/2*k1, k2)
               call rates(e + rate*h/2, y + h/2*k2, k3)
               call rates(e + rate*h, y + h*k3, k4)
               y = y + h/6*(k1 + 2*k2 + 2*k3 + k4)
            end do
            t = io*nsub*h
            e = ek(seg) + rate*t
            write (output_unit, '(3es24.15)') tk(seg) + t, e, m%youngs*(e - y(1))
         end do
      end do
   end subroutine run

   subroutine rates(e, y, ydot)
      real(dp), intent(in) :: e, y(chaboche_n_uniaxial)
      real(dp), intent(out) :: ydot(chaboche_n_uniaxial)
      call chaboche_uniaxial_rates(m, m%youngs*(e - y(1)), -m%youngs, y, ydot)
   end subroutine rates
end program bench_chaboche
