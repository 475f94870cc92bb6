!> The &solver group: which integrator simulates the tests and its tolerances and step limits.
!> Defaults are those of solver_options.
module usharp_input_solver
   use usharp_kinds, only: dp
   use usharp_error, only: error_type
   use usharp_strings, only: lower
   use usharp_simulation, only: solver_options
   use usharp_namelist, only: nml_file, group_text, find_group, group_error, read_error, check_length, value_len
   implicit none
   private

   public :: read_solver_group, write_solver_defaults

contains

   !> Read &solver (optional) into solver
   subroutine read_solver_group(file, solver, error)
      type(nml_file), intent(in) :: file
      type(solver_options), intent(out) :: solver
      type(error_type), allocatable, intent(out) :: error
      character(len=value_len) :: integrator
      integer :: ios, k
      character(len=512) :: msg
      character(len=:), allocatable :: lines(:)
      k = find_group(file, 'solver')
      if (k > 0) then
         call group_text(file, k, lines)
         call solver_namelist(solver, integrator, ios, msg, text=lines)
      else
         call solver_namelist(solver, integrator, ios, msg)
      end if
      if (ios /= 0) then
         call read_error(error, file, k, 'solver', ios, msg, reread)
         return
      end if
      call check_length(error, file%path//': &solver: ', 'integrator', integrator)
      if (allocated(error)) return
      integrator = lower(integrator)
      if (integrator /= 'cvode' .and. integrator /= 'rodas4' .and. integrator /= 'umat') then
         call fail("integrator = '"//trim(integrator)//"' is not known (cvode, rodas4 or umat)")
      else if (.not. (solver%dt_min > 0.0_dp .and. solver%dt_min <= solver%dt_init .and. &
                      solver%dt_init <= solver%dt_max)) then
         call fail('need 0 < dt_min <= dt_init <= dt_max')
      else if (.not. (solver%rtol >= 0.0_dp .and. solver%rtol < 1.0_dp)) then
         ! 0 (the default) stands for the integrator's own default
         call fail('rtol must lie in (0, 1), or 0 for the default')
      else if (.not. (solver%atol_strain >= 0.0_dp)) then
         call fail('atol_strain must be > 0, or 0 for the default')
      else if (solver%max_step < 0.0_dp .or. solver%max_steps < 1) then
         call fail('max_step must be >= 0 and max_steps >= 1')
      end if
      solver%integrator = trim(integrator)
   contains
      subroutine fail(text)
         character(len=*), intent(in) :: text
         call group_error(error, file%path, 'solver', text)
      end subroutine fail

      subroutine reread(lines, ios, msg)
         character(len=*), intent(in) :: lines(:)
         integer, intent(out) :: ios
         character(len=*), intent(out) :: msg
         type(solver_options) :: scratch
         character(len=value_len) :: given
         call solver_namelist(scratch, given, ios, msg, text=lines)
      end subroutine reread
   end subroutine read_solver_group

   !> Write &solver with its defaults to unit
   subroutine write_solver_defaults(unit)
      integer, intent(in) :: unit
      type(solver_options) :: solver
      character(len=value_len) :: integrator
      integer :: ios
      character(len=512) :: msg
      call solver_namelist(solver, integrator, ios, msg, unit=unit)
   end subroutine write_solver_defaults

   !> The &solver namelist, starting from solver_options' defaults: read from text, or
   !> written to unit; integrator comes back as given (solver%integrator is short)
   subroutine solver_namelist(options, integrator_given, ios, msg, text, unit)
      type(solver_options), intent(out) :: options
      character(len=*), intent(out) :: integrator_given
      integer, intent(out) :: ios
      character(len=*), intent(out) :: msg
      character(len=*), intent(in), optional :: text(:)
      integer, intent(in), optional :: unit
      character(len=value_len) :: integrator
      real(dp) :: rtol, atol_strain, max_step, dt_init, dt_min, dt_max
      integer :: max_steps
      namelist /solver/ integrator, rtol, atol_strain, max_step, max_steps, dt_init, dt_min, dt_max
      integrator = options%integrator
      rtol = options%rtol
      atol_strain = options%atol_strain
      max_step = options%max_step
      max_steps = options%max_steps
      dt_init = options%dt_init
      dt_min = options%dt_min
      dt_max = options%dt_max
      ios = 0
      msg = ''
      if (present(text)) read (text, nml=solver, iostat=ios, iomsg=msg)
      if (present(unit)) write (unit, nml=solver, iostat=ios, iomsg=msg)
      integrator_given = integrator
      options%rtol = rtol
      options%atol_strain = atol_strain
      options%max_step = max_step
      options%max_steps = max_steps
      options%dt_init = dt_init
      options%dt_min = dt_min
      options%dt_max = dt_max
   end subroutine solver_namelist

end module usharp_input_solver
