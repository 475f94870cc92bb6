!> Solver settings and simulation results shared by the integrators
module usharp_simulation
   use usharp_kinds, only: dp, i8
   implicit none
   private

   public :: solver_options, sim_result

   !> Integrator settings
   type :: solver_options
      !> 'cvode' (BDF), 'rodas4' (Rosenbrock, one step) or 'umat' (implicit stress update)
      character(len=8) :: integrator = 'cvode'
      real(dp) :: rtol = 1.0e-7_dp         !< relative tolerance
      real(dp) :: atol_strain = 1.0e-10_dp !< absolute tolerance on strain; stresses get E times it
      real(dp) :: max_step = 0.0_dp        !< largest step, s (0: no limit)
      integer :: max_steps = 500000        !< most steps between two outputs
      !> Time increments of the umat path, s, as the original APDL deck: initial, min, max
      real(dp) :: dt_init = 0.1_dp, dt_min = 1.0e-8_dp, dt_max = 0.15_dp
   end type solver_options

   !> Response at the output times
   type :: sim_result
      real(dp), allocatable :: t(:)       !< s
      real(dp), allocatable :: strain(:)  !< total strain, -
      real(dp), allocatable :: stress(:)  !< model unit
      real(dp), allocatable :: eps_in(:)  !< inelastic strain, -
      real(dp), allocatable :: back(:)    !< back stress R, model unit
      real(dp), allocatable :: drag(:)    !< drag stress D, model unit
      integer(i8) :: nsteps = 0, nrhs = 0, njac = 0
   contains
      procedure :: allocate => result_allocate
   end type sim_result

contains

   !> Allocate for n output points
   pure subroutine result_allocate(self, n)
      class(sim_result), intent(inout) :: self
      integer, intent(in) :: n
      if (allocated(self%t)) deallocate (self%t, self%strain, self%stress, self%eps_in, &
                                          self%back, self%drag)
      allocate (self%t(n), self%strain(n), self%stress(n), self%eps_in(n), self%back(n), &
                self%drag(n))
   end subroutine result_allocate
end module usharp_simulation
