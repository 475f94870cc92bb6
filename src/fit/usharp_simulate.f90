!> Simulating one configured test: output times, the integrator, error context
module usharp_simulate
   use usharp_kinds, only: dp
   use usharp_error, only: error_type, prefix_error, fatal_error, stat_failure
   use usharp_model, only: model_type, model_at
   use usharp_simulation, only: solver_options, sim_result
   use usharp_cvode_driver, only: simulate_cvode
   use usharp_rosenbrock_driver, only: simulate_rosenbrock
   use usharp_umat_driver, only: simulate_umat
   use usharp_config, only: test_config, test_increments
   use usharp_rng, only: rng_type
   use usharp_strings, only: real_str
   use usharp_history, only: control_stress
   implicit none
   private

   !> The largest strain a simulation may reach (-): beyond 1 (100 %) a small-strain model
   !> describes no test, and a creep test at a stress far above its range runs away to 1e38
   !> in seconds, which the integrator follows with its error in control
   real(dp), parameter :: runaway_strain = 1.0_dp

   public :: simulate_test, add_response_noise, model_lines, test_model

contains

   !> Simulate a test at its output interval with the chosen integrator, at the test's own
   !> temperature if it has one; errors name the test
   subroutine simulate_test(model, solver, test, res, error)
      class(model_type), intent(in) :: model
      type(solver_options), intent(in) :: solver
      type(test_config), intent(in) :: test
      type(sim_result), intent(out) :: res
      type(error_type), allocatable, intent(out) :: error
      class(model_type), allocatable :: mt
      call test_model(model, test, mt, error)
      if (.not. allocated(error)) call simulate_with(mt)
      if (.not. allocated(error)) call check_runaway()
      if (allocated(error)) call prefix_error(error, "test '"//test%name//"': ")
   contains
      !> A response beyond runaway_strain is a failed simulation, not a result
      subroutine check_runaway()
         integer :: k
         if (.not. allocated(res%strain)) return
         if (size(res%strain) == 0) return
         k = maxloc(abs(res%strain), 1)
         if (abs(res%strain(k)) > runaway_strain) call fatal_error(error, 'the response ran away: '// &
            'the strain reaches '//real_str(res%strain(k), 'es10.3')//' at t = '//real_str(res%t(k), 'es10.3')// &
            ' s, beyond what this small-strain model describes (1, 100 %): the load or the constants '// &
            'lie outside its range', stat_failure)
      end subroutine check_runaway
      subroutine simulate_with(m)
         class(model_type), intent(in) :: m
         if (allocated(test%hist%temp) .and. solver%integrator /= 'rodas4') then
            call fatal_error(error, "a temperature cycle (tmf_temperatures) needs integrator "// &
                             "= 'rodas4', not '"//trim(solver%integrator)//"'")
         else if (solver%integrator == 'umat') then
            call simulate_umat(m, test%hist, test%times(), test_increments(test, solver), res, error)
         else if (solver%integrator == 'rodas4') then
            call simulate_rosenbrock(m, test%hist, test%times(), solver, &
                                     res, error)
         else
            call simulate_cvode(m, test%hist, test%times(), solver, res, error)
         end if
      end subroutine simulate_with
   end subroutine simulate_test

   !> Add Gaussian noise to the measured response of a simulated test, sd = level times its
   !> largest magnitude: the stress of a strain-controlled test, the strain of a
   !> stress-controlled one (creep), whose stress is the command
   subroutine add_response_noise(res, control, level, seed)
      type(sim_result), intent(inout) :: res
      !> the test's control (control_strain or control_stress)
      integer, intent(in) :: control
      real(dp), intent(in) :: level
      integer, intent(in) :: seed
      if (level <= 0.0_dp) return
      if (control == control_stress) then
         call add_to(res%strain)
      else
         call add_to(res%stress)
      end if
   contains
      subroutine add_to(y)
         real(dp), intent(inout) :: y(:)
         type(rng_type) :: rng
         real(dp) :: scale
         integer :: i
         call rng%seed(seed)
         scale = level*maxval(abs(y))
         do i = 1, size(y)
            y(i) = y(i) + scale*rng%normal()
         end do
      end subroutine add_to
   end subroutine add_response_noise

   !> The model as test sees it: at the test's own temperature where it has one (its drag
   !> stress's start D0 and the rates' temperature factor follow), else model itself
   subroutine test_model(model, test, mt, error)
      class(model_type), intent(in) :: model
      type(test_config), intent(in) :: test
      class(model_type), allocatable, intent(out) :: mt
      type(error_type), allocatable, intent(out) :: error
      if (test%temperature > 0.0_dp) then
         call model_at(model, test%temperature, mt, error)
      else
         allocate (mt, source=model)
      end if
   end subroutine test_model

   !> The two header lines of a test's simulation file that say what made it: the model at
   !> the test's temperature (T, Tm, E and the derived values; a temperature cycle from its
   !> start) and every constant
   function model_lines(model, units, test, error) result(lines)
      class(model_type), intent(in) :: model
      !> the model's stress unit
      character(len=*), intent(in) :: units
      type(test_config), intent(in) :: test
      type(error_type), allocatable, intent(out) :: error
      character(len=512) :: lines(2)
      class(model_type), allocatable :: mt
      character(len=:), allocatable :: line
      character(len=:), allocatable :: dnames(:)
      real(dp), allocatable :: dvals(:)
      integer :: k
      line = 'model '//model%name()//', T = '//real_str(merge(test%temperature, &
             model%temperature, test%temperature > 0.0_dp), 'g0.8')//' K, Tm = '// &
             real_str(model%tm, 'g0.8')//' K, E = '//real_str(model%youngs, 'g0.8')//' '//units
      if (allocated(test%hist%temp)) line = line//' (at the start; the temperature follows '// &
         'the command from '//real_str(minval(test%hist%temp), 'g0.8')//' to '// &
         real_str(maxval(test%hist%temp), 'g0.8')//' K)'
      ! (the model as the test starts: a test at its own temperature, a temperature cycle at
      ! its first, is set up there)
      call test_model(model, test, mt, error)
      if (allocated(error)) return
      call mt%derived_values(dnames, dvals)
      do k = 1, size(dvals)
         line = line//', '//trim(dnames(k))//' = '//real_str(dvals(k), 'g0.8')//' '//units
      end do
      lines(1) = line
      line = 'constants:'
      do k = 1, model%n_constants()
         line = line//' '//model%constant_name(k)//' = '//real_str(model%get_constant(k), 'es12.5')
      end do
      lines(2) = line
   end function model_lines

end module usharp_simulate
