!> The &fit group: which constants are fitted, by which method, within which bounds
module usharp_input_fit
   use usharp_kinds, only: dp
   use usharp_error, only: error_type
   use usharp_strings, only: lower_text => lower, str
   use usharp_model, only: model_type, constant_index
   use usharp_units, only: stress_factor
   use usharp_namelist, only: nml_file, group_text, find_group, group_error, read_error, check_length, &
                              value_len, max_list, unset
   implicit none
   private

   public :: fit_config, read_fit_group, write_fit_defaults

   !> Fit settings (&fit group)
   type :: fit_config
      logical, allocatable :: fitted(:)            !< which constants are searched (model order)
      character(len=16) :: method = 'hooke-jeeves' !< hooke-jeeves, lm, nelder-mead, anneal
      character(len=4) :: objective = 'eq7'        !< eq7 or eq13
      real(dp) :: rho = 0.5_dp
      real(dp) :: eps = 1.0e-6_dp
      integer :: itermax = 1000
      integer :: max_evals = 100000
      integer :: max_failures = 100                !< failures in a row before the fit aborts
      logical :: log_search = .false.
      !> Search bounds (physical units); lm, nelder-mead, anneal and multistart keep to them
      real(dp), allocatable :: lower(:), upper(:)
      !> Box of the multi-start points (physical units)
      real(dp), allocatable :: box_lower(:), box_upper(:)
      integer :: multistart = 0                    !< number of Latin-hypercube starts (0: none)
      integer :: seed = 1                          !< seed of multi-start and annealing
      real(dp) :: fd_step = 1.0e-3_dp              !< forward-difference step in log10 of a constant
      !> Jacobian of Levenberg-Marquardt: 'difference' (forward differences, one simulation
      !> per constant) or 'sensitivity' (CVODES forward sensitivities, one simulation)
      character(len=16) :: jacobian = 'difference'
      real(dp) :: anneal_t0 = 0.0_dp               !< initial temperature (0: the start objective)
      real(dp) :: anneal_rt = 0.85_dp              !< temperature reduction factor
      logical :: identify = .true.                 !< identifiability report after the fit
      logical :: present = .false.                 !< the input has a &fit group
   end type fit_config

   !> The &fit lists as given: names of the fitted constants and their bounds in that order
   type :: fit_lists
      character(len=value_len) :: fitted(max_list)
      character(len=value_len) :: method, objective, jacobian
      real(dp) :: lower(max_list), upper(max_list), box_lower(max_list), box_upper(max_list)
   end type fit_lists

contains

   !> Read &fit (optional) into fit; units: the model's stress unit (of the default bounds)
   subroutine read_fit_group(file, units, model, fit, error)
      type(nml_file), intent(in) :: file
      character(len=*), intent(in) :: units
      class(model_type), intent(in) :: model
      type(fit_config), intent(out) :: fit
      type(error_type), allocatable, intent(out) :: error
      type(fit_lists) :: given
      integer :: ios, k, i, idx
      real(dp) :: f, low, high
      character(len=512) :: msg, names
      character(len=:), allocatable :: lines(:)
      character(len=:), allocatable :: where, method, objective, jacobian
      ! Defaults: the literature box, and two decades beyond it for the search bounds
      allocate (fit%fitted(model%n_constants()), source=.false.)
      allocate (fit%lower(model%n_constants()), fit%upper(model%n_constants()), &
                fit%box_lower(model%n_constants()), fit%box_upper(model%n_constants()))
      do i = 1, model%n_constants()
         f = stress_factor(model%literature_units(), units)**model%stress_power(i)
         call model%literature_range(i, low, high)
         fit%box_lower(i) = low*f
         fit%box_upper(i) = high*f
         fit%lower(i) = 0.01_dp*low*f
         fit%upper(i) = 100.0_dp*high*f
      end do
      k = find_group(file, 'fit')
      fit%present = k > 0
      if (k > 0) then
         call group_text(file, k, lines)
         call fit_namelist(fit, given, ios, msg, text=lines)
      else
         call fit_namelist(fit, given, ios, msg)
      end if
      if (ios /= 0) then
         call read_error(error, file, k, 'fit', ios, msg, reread)
         return
      end if
      where = file%path//': &fit: '
      do i = 1, max_list
         call check_length(error, where, 'fitted', given%fitted(i))
      end do
      call check_length(error, where, 'method', given%method)
      call check_length(error, where, 'objective', given%objective)
      call check_length(error, where, 'jacobian', given%jacobian)
      if (allocated(error)) return
      do i = 1, max_list
         if (len_trim(given%fitted(i)) == 0) then
            ! A bound is given for the i-th fitted constant: one the list does not name
            if (any([given%lower(i), given%upper(i), given%box_lower(i), given%box_upper(i)] /= unset)) then
               call fail('a bound ('//trim(bound_names(i))//') is given for fitted constant '// &
                  str(i)//', but fitted names '//str(count(len_trim(given%fitted) > 0))//' constant'// &
                  trim(merge('s', ' ', count(len_trim(given%fitted) > 0) /= 1)))
               return
            end if
            cycle
         end if
         idx = constant_index(model, given%fitted(i))
         if (idx == 0) then
            names = model%constant_name(1)
            do k = 2, model%n_constants()
               names = trim(names)//', '//model%constant_name(k)
            end do
            call fail("fitted = '"//trim(given%fitted(i))//"' is not a constant ("//trim(names)//")")
            return
         end if
         if (fit%fitted(idx)) then
            call fail("fitted names '"//trim(model%constant_name(idx))//"' twice")
            return
         end if
         fit%fitted(idx) = .true.
         ! Bounds in the order of fitted
         if (given%lower(i) /= unset) fit%lower(idx) = given%lower(i)
         if (given%upper(i) /= unset) fit%upper(idx) = given%upper(i)
         if (given%box_lower(i) /= unset) fit%box_lower(idx) = given%box_lower(i)
         if (given%box_upper(i) /= unset) fit%box_upper(idx) = given%box_upper(i)
         if (.not. (0.0_dp < fit%lower(idx) .and. fit%lower(idx) < fit%upper(idx) .and. &
                    0.0_dp < fit%box_lower(idx) .and. fit%box_lower(idx) < fit%box_upper(idx))) then
            call fail('the bounds of '//trim(given%fitted(i))// &
               ' must satisfy 0 < lower < upper and 0 < box_lower < box_upper')
            return
         end if
      end do
      method = lower_text(trim(given%method))
      jacobian = lower_text(trim(given%jacobian))
      objective = lower_text(trim(given%objective))
      select case (method)
      case ('hooke-jeeves', 'lm', 'nelder-mead', 'anneal')
      case default
         call fail("method = '"//method//"' is not known (hooke-jeeves, lm, nelder-mead, anneal)")
         return
      end select
      if (jacobian /= 'difference' .and. jacobian /= 'sensitivity') then
         call fail("jacobian = '"//jacobian//"' is not known (difference, sensitivity)")
      else if (fit%multistart < 0) then
         call fail('multistart = '//str(fit%multistart)//' must be >= 0')
      else if (.not. (fit%fd_step > 0.0_dp .and. fit%fd_step < 0.1_dp)) then
         call fail('fd_step must lie in (0, 0.1)')
      else if (.not. (fit%anneal_rt > 0.0_dp .and. fit%anneal_rt < 1.0_dp)) then
         call fail('anneal_rt must lie in (0, 1)')
      else if (.not. (fit%anneal_t0 >= 0.0_dp)) then
         call fail('anneal_t0 must be >= 0')
      else if (objective /= 'eq7' .and. objective /= 'eq13') then
         call fail("objective = '"//objective//"' is not known (eq7 or eq13)")
      else if (.not. (fit%rho > 0.0_dp .and. fit%rho < 1.0_dp)) then
         call fail('rho must lie in (0, 1)')
      else if (.not. (fit%eps > 0.0_dp) .or. fit%itermax < 1 .or. fit%max_evals < 1 .or. &
               fit%max_failures < 1) then
         call fail('eps must be > 0 and itermax, max_evals, max_failures >= 1')
      end if
      if (allocated(error)) return
      fit%method = method
      fit%objective = objective
      fit%jacobian = jacobian
      ! The methods other than the original's search in log10 of the constants
      if (method /= 'hooke-jeeves') fit%log_search = .true.
   contains
      subroutine fail(text)
         character(len=*), intent(in) :: text
         call group_error(error, file%path, 'fit', text)
      end subroutine fail

      !> The bounds given at position i of the lists, as the deck writes them
      function bound_names(i) result(names)
         integer, intent(in) :: i
         character(len=:), allocatable :: names
         names = ''
         if (given%lower(i) /= unset) names = names//', lower('//str(i)//')'
         if (given%upper(i) /= unset) names = names//', upper('//str(i)//')'
         if (given%box_lower(i) /= unset) names = names//', box_lower('//str(i)//')'
         if (given%box_upper(i) /= unset) names = names//', box_upper('//str(i)//')'
         names = names(3:)
      end function bound_names

      subroutine reread(lines, ios, msg)
         character(len=*), intent(in) :: lines(:)
         integer, intent(out) :: ios
         character(len=*), intent(out) :: msg
         type(fit_config) :: scratch
         type(fit_lists) :: lists
         call fit_namelist(scratch, lists, ios, msg, text=lines)
      end subroutine reread
   end subroutine read_fit_group

   !> Write &fit with its defaults to unit (bounds unset: -huge)
   subroutine write_fit_defaults(unit)
      integer, intent(in) :: unit
      type(fit_config) :: fit
      type(fit_lists) :: given
      integer :: ios
      character(len=512) :: msg
      call fit_namelist(fit, given, ios, msg, unit=unit)
   end subroutine write_fit_defaults

   !> The &fit namelist, starting from fit (no constant fitted, bounds unset): read from text
   !> or written to unit. The lists and names come back as given, to be checked.
   subroutine fit_namelist(settings, given, ios, msg, text, unit)
      type(fit_config), intent(inout) :: settings
      type(fit_lists), intent(out) :: given
      integer, intent(out) :: ios
      character(len=*), intent(out) :: msg
      character(len=*), intent(in), optional :: text(:)
      integer, intent(in), optional :: unit
      character(len=value_len) :: fitted(max_list), method, objective, jacobian
      real(dp) :: rho, eps, lower(max_list), upper(max_list), box_lower(max_list), &
                  box_upper(max_list), fd_step, anneal_t0, anneal_rt
      integer :: itermax, max_evals, max_failures, multistart, seed
      logical :: log_search, identify
      namelist /fit/ fitted, method, objective, rho, eps, itermax, max_evals, max_failures, &
         log_search, lower, upper, box_lower, box_upper, multistart, seed, fd_step, anneal_t0, &
         anneal_rt, identify, jacobian
      fitted = ''
      lower = unset; upper = unset; box_lower = unset; box_upper = unset
      method = settings%method
      objective = settings%objective
      jacobian = settings%jacobian
      rho = settings%rho
      eps = settings%eps
      itermax = settings%itermax
      max_evals = settings%max_evals
      max_failures = settings%max_failures
      log_search = settings%log_search
      multistart = settings%multistart
      seed = settings%seed
      fd_step = settings%fd_step
      anneal_t0 = settings%anneal_t0
      anneal_rt = settings%anneal_rt
      identify = settings%identify
      ios = 0
      msg = ''
      if (present(text)) read (text, nml=fit, iostat=ios, iomsg=msg)
      if (present(unit)) write (unit, nml=fit, iostat=ios, iomsg=msg)
      given = fit_lists(fitted, method, objective, jacobian, lower, upper, box_lower, box_upper)
      settings%rho = rho
      settings%eps = eps
      settings%itermax = itermax
      settings%max_evals = max_evals
      settings%max_failures = max_failures
      settings%log_search = log_search
      settings%multistart = multistart
      settings%seed = seed
      settings%fd_step = fd_step
      settings%anneal_t0 = anneal_t0
      settings%anneal_rt = anneal_rt
      settings%identify = identify
   end subroutine fit_namelist

end module usharp_input_fit
