!> Reading a usharp input file: Fortran namelist groups &model, &constants, &solver, &output,
!> &fit and one &test group per test. Every error names the file, the group and the variable.
module usharp_input
   use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
   use usharp_kinds, only: dp
   use usharp_error, only: error_type, fatal_error, prefix_error, stat_input
   use usharp_strings, only: lower_text => lower, str
   use usharp_miller, only: miller_model, n_constants, constant_index, model_setup, &
                            miller_constants, literature_low, literature_high, stress_power
   use usharp_forcing, only: measured_history
   use usharp_history, only: history_type, control_strain, control_stress, history_from_points, &
                             thesis_lcf_history, relaxation_history, ratchet_history, &
                             cyclic_history, tensile_history, creep_history, rate_jump_history
   use usharp_table, only: read_columns, merge_repeated_times
   use usharp_units, only: ksi_to_mpa, stress_factor
   use usharp_config, only: run_config, test_config, data_spec, fit_config, external_spec, max_list
   implicit none
   private

   public :: read_config, resolve_path, known_groups, read_data_columns, override_constants
   public :: read_config_as

   character(len=9), parameter :: known_groups(8) = &
      ['model    ', 'constants', 'solver   ', 'output   ', 'fit      ', 'test     ', 'design   ', 'diagnose ']
   real(dp), parameter :: unset = -huge(1.0_dp)
   integer, parameter :: name_len = 256

contains

   !> Read and check the input file; histories are built, data files are not yet read
   subroutine read_config(path, cfg, error)
      character(len=*), intent(in) :: path
      type(run_config), intent(out) :: cfg
      type(error_type), allocatable, intent(out) :: error
      integer :: unit, ios, ntest_groups
      logical :: exists
      character(len=512) :: msg

      inquire (file=path, exist=exists)
      if (.not. exists) then
         call fatal_error(error, path//': no such input file')
         return
      end if
      open (newunit=unit, file=path, status='old', action='read', iostat=ios, iomsg=msg)
      if (ios /= 0) then
         call fatal_error(error, path//': cannot open ('//trim(msg)//')')
         return
      end if
      cfg%path = path
      cfg%base_dir = dirname(path)
      call check_groups(unit, path, ntest_groups, error)
      if (.not. allocated(error)) call read_model(unit, cfg, error)
      if (.not. allocated(error)) call read_constants(unit, cfg, error)
      if (.not. allocated(error)) call read_solver(unit, cfg, error)
      if (.not. allocated(error)) call read_output(unit, cfg, error)
      if (.not. allocated(error)) call read_fit(unit, cfg, error)
      if (.not. allocated(error)) call read_design(unit, cfg, error)
      if (.not. allocated(error)) call read_diagnose(unit, cfg, error)
      if (.not. allocated(error)) call read_tests(unit, cfg, error)
      ! A group without its closing '/' reads as the end of the file
      if (.not. allocated(error)) then
         if (size(cfg%tests) < ntest_groups) call fatal_error(error, path//': &test #'// &
            str(size(cfg%tests) + 1)//" is not terminated by '/'")
      end if
      close (unit)
      if (allocated(error)) return
      call model_setup(cfg%model, error)
      if (allocated(error)) call prefix_error(error, path//': &constants: ')
   end subroutine read_config

   !> read_config, then the command line's choices: the constants of another file (a
   !> best.nml; '' for none) and another output folder ('' for &output's)
   subroutine read_config_as(path, constants_file, out_dir, cfg, error)
      character(len=*), intent(in) :: path, constants_file, out_dir
      type(run_config), intent(out) :: cfg
      type(error_type), allocatable, intent(out) :: error
      call read_config(path, cfg, error)
      if (allocated(error)) return
      if (len_trim(constants_file) > 0) then
         call override_constants(cfg, constants_file, error)
         if (allocated(error)) return
      end if
      if (len_trim(out_dir) > 0) cfg%out_dir = trim(out_dir)
   end subroutine read_config_as

   !> Replace the constants of cfg by the &constants group of another file (a best.nml)
   subroutine override_constants(cfg, path, error)
      type(run_config), intent(inout) :: cfg
      character(len=*), intent(in) :: path
      type(error_type), allocatable, intent(out) :: error
      integer :: unit, ios
      character(len=512) :: msg
      character(len=:), allocatable :: main_path
      open (newunit=unit, file=path, status='old', action='read', iostat=ios, iomsg=msg)
      if (ios /= 0) then
         call fatal_error(error, path//': cannot open constants file ('//trim(msg)//')')
         return
      end if
      main_path = cfg%path
      cfg%path = path
      call read_constants(unit, cfg, error)
      cfg%path = main_path
      close (unit)
      if (allocated(error)) return
      call model_setup(cfg%model, error)
      if (allocated(error)) call prefix_error(error, path//': &constants: ')
   end subroutine override_constants

   !> Reject namelist groups that usharp does not know (a misspelt group would be skipped)
   subroutine check_groups(unit, path, ntest, error)
      integer, intent(in) :: unit
      character(len=*), intent(in) :: path
      integer, intent(out) :: ntest  !< number of &test groups
      type(error_type), allocatable, intent(out) :: error
      character(len=1024) :: line
      character(len=64) :: word
      integer :: ios, lineno, col, e
      lineno = 0
      ntest = 0
      rewind (unit)
      do
         read (unit, '(a)', iostat=ios) line
         if (ios /= 0) exit
         lineno = lineno + 1
         col = index(line, '&')
         if (col == 0) cycle
         if (len_trim(line(:col - 1)) > 0) cycle  ! only a group start at the line's beginning
         e = scan(line(col + 1:), ' ,/!') + col
         if (e == col) e = len_trim(line) + 1
         word = lower_text(line(col + 1:e - 1))
         if (len_trim(word) == 0 .or. trim(word) == 'end') cycle
         if (trim(word) == 'test') ntest = ntest + 1
         if (.not. any(trim(word) == known_groups)) then
            call fatal_error(error, path//':'//str(lineno)//':'//str(col)// &
               ': unknown namelist group &'//trim(word)//' (known: &model, &constants, '// &
               '&solver, &output, &fit, &design, &diagnose, &test)')
            return
         end if
      end do
      rewind (unit)
   end subroutine check_groups

   subroutine nml_error(error, path, group, ios, msg)
      type(error_type), allocatable, intent(out) :: error
      character(len=*), intent(in) :: path, group, msg
      integer, intent(in) :: ios
      call fatal_error(error, path//': &'//group//': '//trim(msg)//' (iostat '//str(ios)//')')
   end subroutine nml_error

   subroutine read_model(unit, cfg, error)
      integer, intent(in) :: unit
      type(run_config), intent(inout) :: cfg
      type(error_type), allocatable, intent(out) :: error
      character(len=32) :: name, units
      real(dp) :: temperature, tm, youngs, poisson, d0, d0_yield, d0_rate
      integer :: ios
      character(len=512) :: msg
      namelist /model/ name, units, temperature, tm, youngs, poisson, d0, d0_yield, d0_rate
      name = 'miller'
      units = 'ksi'
      temperature = unset
      tm = unset
      youngs = unset
      poisson = 0.3_dp
      d0 = 0.0_dp
      d0_yield = unset
      d0_rate = 5.0e-5_dp
      rewind (unit)
      read (unit, nml=model, iostat=ios, iomsg=msg)
      if (is_iostat_end(ios)) then
         call fatal_error(error, cfg%path//': group &model is missing')
         return
      else if (ios /= 0) then
         call nml_error(error, cfg%path, 'model', ios, msg)
         return
      end if
      if (lower_text(trim(name)) /= 'miller') then
         call fatal_error(error, cfg%path//": &model: name = '"//trim(name)// &
            "' is not known (known: miller)")
         return
      end if
      units = lower_text(units)
      if (units == 'mpa') units = 'MPa'
      if (units /= 'ksi' .and. units /= 'MPa') then
         call fatal_error(error, cfg%path//": &model: units = '"//trim(units)// &
            "' is not known (ksi or MPa)")
         return
      end if
      cfg%units = trim(units)
      if (required(temperature, 'temperature')) return
      if (required(tm, 'tm')) return
      if (required(youngs, 'youngs')) return
      cfg%model%temperature = temperature
      cfg%model%tm = tm
      cfg%model%youngs = youngs
      cfg%model%poisson = poisson
      cfg%model%d0_fixed = d0
      ! The thesis's YS = 18 ksi in the model's unit unless given
      if (d0_yield == unset) d0_yield = merge(18.0_dp, 18.0_dp*ksi_to_mpa, cfg%units == 'ksi')
      cfg%model%d0_yield = d0_yield
      cfg%model%d0_rate = d0_rate
   contains
      logical function required(val, name) result(missing)
         real(dp), intent(in) :: val
         character(len=*), intent(in) :: name
         missing = val == unset
         if (missing) call fatal_error(error, cfg%path//': &model: '//name//' is not set')
      end function required
   end subroutine read_model

   subroutine read_constants(unit, cfg, error)
      integer, intent(in) :: unit
      type(run_config), intent(inout) :: cfg
      type(error_type), allocatable, intent(out) :: error
      real(dp) :: a1, a2, b, c2, h1, h2, n, q
      integer :: ios
      character(len=512) :: msg
      namelist /constants/ a1, a2, b, c2, h1, h2, n, q
      a1 = unset; a2 = unset; b = unset; c2 = unset
      h1 = unset; h2 = unset; n = unset; q = unset
      rewind (unit)
      read (unit, nml=constants, iostat=ios, iomsg=msg)
      if (is_iostat_end(ios)) then
         call fatal_error(error, cfg%path//': group &constants is missing')
         return
      else if (ios /= 0) then
         call nml_error(error, cfg%path, 'constants', ios, msg)
         return
      end if
      if (any([a1, a2, b, c2, h1, h2, n, q] == unset)) then
         call fatal_error(error, cfg%path//': &constants: every constant must be set '// &
            '(missing: '//missing_names([a1, a2, b, c2, h1, h2, n, q])//')')
         return
      end if
      cfg%model%c = miller_constants(a1, a2, b, c2, h1, h2, n, q)
   contains
      function missing_names(vals) result(text)
         real(dp), intent(in) :: vals(:)
         character(len=:), allocatable :: text
         character(len=2), parameter :: names(8) = ['a1', 'a2', 'b ', 'c2', 'h1', 'h2', 'n ', 'q ']
         integer :: i
         text = ''
         do i = 1, size(vals)
            if (vals(i) == unset) text = text//' '//trim(names(i))
         end do
         text = adjustl(text)
      end function missing_names
   end subroutine read_constants

   subroutine read_solver(unit, cfg, error)
      integer, intent(in) :: unit
      type(run_config), intent(inout) :: cfg
      type(error_type), allocatable, intent(out) :: error
      character(len=32) :: integrator
      real(dp) :: rtol, atol_strain, max_step, dt_init, dt_min, dt_max
      integer :: max_steps, ios
      character(len=512) :: msg
      namelist /solver/ integrator, rtol, atol_strain, max_step, max_steps, dt_init, dt_min, dt_max
      integrator = cfg%solver%integrator
      dt_init = cfg%solver%dt_init
      dt_min = cfg%solver%dt_min
      dt_max = cfg%solver%dt_max
      rtol = cfg%solver%rtol
      atol_strain = cfg%solver%atol_strain
      max_step = cfg%solver%max_step
      max_steps = cfg%solver%max_steps
      rewind (unit)
      read (unit, nml=solver, iostat=ios, iomsg=msg)
      if (ios /= 0 .and. .not. is_iostat_end(ios)) then
         call nml_error(error, cfg%path, 'solver', ios, msg)
         return
      end if
      integrator = lower_text(integrator)
      if (integrator /= 'cvode' .and. integrator /= 'rodas4' .and. integrator /= 'umat') then
         call fatal_error(error, cfg%path//": &solver: integrator = '"//trim(integrator)// &
            "' is not known (cvode, rodas4 or umat)")
         return
      end if
      if (.not. (dt_min > 0.0_dp .and. dt_min <= dt_init .and. dt_init <= dt_max)) then
         call fatal_error(error, cfg%path//': &solver: need 0 < dt_min <= dt_init <= dt_max')
         return
      end if
      cfg%solver%integrator = trim(integrator)
      cfg%solver%dt_init = dt_init
      cfg%solver%dt_min = dt_min
      cfg%solver%dt_max = dt_max
      ! 0 (the default) stands for the integrator's own default
      if (.not. (rtol >= 0.0_dp .and. rtol < 1.0_dp)) then
         call fatal_error(error, cfg%path//': &solver: rtol must lie in (0, 1), or 0 for the default')
         return
      end if
      if (.not. (atol_strain >= 0.0_dp)) then
         call fatal_error(error, cfg%path//': &solver: atol_strain must be > 0, or 0 for the default')
         return
      end if
      if (max_step < 0.0_dp .or. max_steps < 1) then
         call fatal_error(error, cfg%path//': &solver: max_step must be >= 0 and max_steps >= 1')
         return
      end if
      cfg%solver%rtol = rtol
      cfg%solver%atol_strain = atol_strain
      cfg%solver%max_step = max_step
      cfg%solver%max_steps = max_steps
   end subroutine read_solver

   subroutine read_output(unit, cfg, error)
      integer, intent(in) :: unit
      type(run_config), intent(inout) :: cfg
      type(error_type), allocatable, intent(out) :: error
      character(len=name_len) :: out_dir
      integer :: ios
      character(len=512) :: msg
      namelist /output/ out_dir
      out_dir = 'out'
      rewind (unit)
      read (unit, nml=output, iostat=ios, iomsg=msg)
      if (ios /= 0 .and. .not. is_iostat_end(ios)) then
         call nml_error(error, cfg%path, 'output', ios, msg)
         return
      end if
      if (len_trim(out_dir) == 0) then
         call fatal_error(error, cfg%path//': &output: out_dir is empty')
         return
      end if
      cfg%out_dir = resolve_path(cfg%base_dir, trim(out_dir))
   end subroutine read_output

   subroutine read_fit(unit, cfg, error)
      integer, intent(in) :: unit
      type(run_config), intent(inout) :: cfg
      type(error_type), allocatable, intent(out) :: error
      character(len=16) :: fitted(max_list)
      character(len=32) :: method, objective, jacobian
      real(dp) :: rho, eps, lower(max_list), upper(max_list), box_lower(max_list), &
                  box_upper(max_list), fd_step, anneal_t0, anneal_rt, f
      integer :: itermax, max_evals, max_failures, ios, i, idx, multistart, seed
      logical :: log_search, identify
      character(len=512) :: msg
      namelist /fit/ fitted, method, objective, rho, eps, itermax, max_evals, max_failures, &
         log_search, lower, upper, box_lower, box_upper, multistart, seed, fd_step, anneal_t0, &
         anneal_rt, identify, jacobian
      fitted = ''
      jacobian = cfg%fit%jacobian
      lower = unset; upper = unset; box_lower = unset; box_upper = unset
      multistart = 0; seed = 1; fd_step = cfg%fit%fd_step; anneal_t0 = 0.0_dp
      anneal_rt = cfg%fit%anneal_rt; identify = .true.
      ! Defaults: the literature box, and two decades beyond it for the search bounds
      do i = 1, n_constants
         f = stress_factor('ksi', cfg%units)**stress_power(i)
         cfg%fit%box_lower(i) = literature_low(i)*f
         cfg%fit%box_upper(i) = literature_high(i)*f
         cfg%fit%lower(i) = 0.01_dp*literature_low(i)*f
         cfg%fit%upper(i) = 100.0_dp*literature_high(i)*f
      end do
      method = 'hooke-jeeves'
      objective = 'eq7'
      rho = cfg%fit%rho
      eps = cfg%fit%eps
      itermax = cfg%fit%itermax
      max_evals = cfg%fit%max_evals
      max_failures = cfg%fit%max_failures
      log_search = cfg%fit%log_search
      rewind (unit)
      read (unit, nml=fit, iostat=ios, iomsg=msg)
      if (ios /= 0 .and. .not. is_iostat_end(ios)) then
         call nml_error(error, cfg%path, 'fit', ios, msg)
         return
      end if
      do i = 1, max_list
         if (len_trim(fitted(i)) == 0) cycle
         idx = constant_index(fitted(i))
         if (idx == 0) then
            call fatal_error(error, cfg%path//": &fit: fitted = '"//trim(fitted(i))// &
               "' is not a constant (A1, A2, B, C2, H1, H2, n, Q)")
            return
         end if
         cfg%fit%fitted(idx) = .true.
         ! Bounds in the order of fitted
         if (lower(i) /= unset) cfg%fit%lower(idx) = lower(i)
         if (upper(i) /= unset) cfg%fit%upper(idx) = upper(i)
         if (box_lower(i) /= unset) cfg%fit%box_lower(idx) = box_lower(i)
         if (box_upper(i) /= unset) cfg%fit%box_upper(idx) = box_upper(i)
         if (.not. (0.0_dp < cfg%fit%lower(idx) .and. cfg%fit%lower(idx) < cfg%fit%upper(idx) .and. &
                    0.0_dp < cfg%fit%box_lower(idx) .and. cfg%fit%box_lower(idx) < cfg%fit%box_upper(idx))) then
            call fatal_error(error, cfg%path//': &fit: the bounds of '//trim(fitted(i))// &
               ' must satisfy 0 < lower < upper and 0 < box_lower < box_upper')
            return
         end if
      end do
      method = lower_text(method)
      select case (method)
      case ('hooke-jeeves', 'lm', 'nelder-mead', 'anneal')
      case default
         call fatal_error(error, cfg%path//": &fit: method = '"//trim(method)// &
            "' is not known (hooke-jeeves, lm, nelder-mead, anneal)")
         return
      end select
      jacobian = lower_text(jacobian)
      if (jacobian /= 'difference' .and. jacobian /= 'sensitivity') then
         call fatal_error(error, cfg%path//": &fit: jacobian = '"//trim(jacobian)// &
            "' is not known (difference, sensitivity)")
         return
      end if
      cfg%fit%jacobian = trim(jacobian)
      if (multistart < 0 .or. .not. (fd_step > 0.0_dp .and. fd_step < 0.1_dp) .or. &
          .not. (anneal_rt > 0.0_dp .and. anneal_rt < 1.0_dp) .or. anneal_t0 < 0.0_dp) then
         call fatal_error(error, cfg%path//': &fit: needs multistart >= 0, 0 < fd_step < 0.1, '// &
            '0 < anneal_rt < 1 and anneal_t0 >= 0')
         return
      end if
      cfg%fit%multistart = multistart
      cfg%fit%seed = seed
      cfg%fit%fd_step = fd_step
      cfg%fit%anneal_t0 = anneal_t0
      cfg%fit%anneal_rt = anneal_rt
      cfg%fit%identify = identify
      objective = lower_text(objective)
      if (objective /= 'eq7' .and. objective /= 'eq13') then
         call fatal_error(error, cfg%path//": &fit: objective = '"//trim(objective)// &
            "' is not known (eq7 or eq13)")
         return
      end if
      if (.not. (rho > 0.0_dp .and. rho < 1.0_dp)) then
         call fatal_error(error, cfg%path//': &fit: rho must lie in (0, 1)')
         return
      end if
      if (.not. (eps > 0.0_dp) .or. itermax < 1 .or. max_evals < 1 .or. max_failures < 1) then
         call fatal_error(error, cfg%path//': &fit: eps must be > 0 and itermax, max_evals, '// &
            'max_failures >= 1')
         return
      end if
      cfg%fit%method = trim(method)
      cfg%fit%objective = trim(objective)
      cfg%fit%rho = rho
      cfg%fit%eps = eps
      cfg%fit%itermax = itermax
      cfg%fit%max_evals = max_evals
      cfg%fit%max_failures = max_failures
      cfg%fit%log_search = log_search
      ! The methods other than the original's search in log10 of the constants
      if (method /= 'hooke-jeeves') cfg%fit%log_search = .true.
   end subroutine read_fit

   subroutine read_diagnose(unit, cfg, error)
      integer, intent(in) :: unit
      type(run_config), intent(inout) :: cfg
      type(error_type), allocatable, intent(out) :: error
      character(len=64) :: holdout(max_list), specimen
      character(len=16) :: effects(max_list), rows(max_list)
      real(dp) :: dlnE_dT, gamma3, confirm_shrink, noise
      integer :: n_refit, refit_starts, global_starts, reps, seed, ios
      logical :: cross_starts
      character(len=512) :: msg
      namelist /diagnose/ holdout, effects, rows, n_refit, refit_starts, global_starts, dlnE_dT, gamma3, &
         cross_starts, confirm_shrink, reps, seed, noise, specimen
      holdout = cfg%diagnose%holdout
      specimen = cfg%diagnose%specimen
      effects = cfg%diagnose%effects
      rows = cfg%diagnose%rows
      n_refit = cfg%diagnose%n_refit
      refit_starts = cfg%diagnose%refit_starts
      global_starts = cfg%diagnose%global_starts
      cross_starts = cfg%diagnose%cross_starts
      dlnE_dT = cfg%diagnose%dlnE_dT
      gamma3 = cfg%diagnose%gamma3
      confirm_shrink = cfg%diagnose%confirm_shrink
      reps = cfg%diagnose%reps
      seed = cfg%diagnose%seed
      noise = cfg%diagnose%noise
      rewind (unit)
      read (unit, nml=diagnose, iostat=ios, iomsg=msg)
      if (ios /= 0 .and. .not. is_iostat_end(ios)) then
         call nml_error(error, cfg%path, 'diagnose', ios, msg)
         return
      end if
      if (n_refit < 1) then
         call fatal_error(error, cfg%path//': &diagnose: n_refit must be >= 1')
      else if (refit_starts < 1) then
         call fatal_error(error, cfg%path//': &diagnose: refit_starts must be >= 1')
      else if (global_starts < 0) then
         call fatal_error(error, cfg%path//': &diagnose: global_starts must be >= 0')
      else if (reps < 1) then
         call fatal_error(error, cfg%path//': &diagnose: reps must be >= 1')
      end if
      if (allocated(error)) return
      if (.not. (gamma3 > 0.0_dp) .or. .not. (noise > 0.0_dp)) then
         call fatal_error(error, cfg%path//': &diagnose: gamma3 and noise must be > 0')
         return
      end if
      if (.not. (confirm_shrink > 0.0_dp .and. confirm_shrink <= 1.0_dp)) then
         call fatal_error(error, cfg%path//': &diagnose: confirm_shrink must lie in (0, 1]')
         return
      end if
      cfg%diagnose%holdout = holdout
      cfg%diagnose%effects = effects
      cfg%diagnose%rows = rows
      cfg%diagnose%n_refit = n_refit
      cfg%diagnose%refit_starts = refit_starts
      cfg%diagnose%global_starts = global_starts
      cfg%diagnose%cross_starts = cross_starts
      cfg%diagnose%dlnE_dT = dlnE_dT
      cfg%diagnose%gamma3 = gamma3
      cfg%diagnose%confirm_shrink = confirm_shrink
      cfg%diagnose%reps = reps
      cfg%diagnose%seed = seed
      cfg%diagnose%noise = noise
      cfg%diagnose%specimen = specimen
   end subroutine read_diagnose

   subroutine read_design(unit, cfg, error)
      integer, intent(in) :: unit
      type(run_config), intent(inout) :: cfg
      type(error_type), allocatable, intent(out) :: error
      real(dp) :: noise, ci_target, prior_decades
      integer :: max_tests, top, ios
      character(len=512) :: msg
      namelist /design/ noise, max_tests, ci_target, prior_decades, top
      noise = cfg%design%noise
      max_tests = cfg%design%max_tests
      ci_target = cfg%design%ci_target
      prior_decades = cfg%design%prior_decades
      top = cfg%design%top
      rewind (unit)
      read (unit, nml=design, iostat=ios, iomsg=msg)
      if (ios /= 0 .and. .not. is_iostat_end(ios)) then
         call nml_error(error, cfg%path, 'design', ios, msg)
         return
      end if
      if (.not. (noise > 0.0_dp)) then
         call fatal_error(error, cfg%path//': &design: noise must be > 0 (a fraction of the '// &
            'peak response, 0.01 for 1 %)')
         return
      end if
      if (max_tests < 1 .or. top < 1) then
         call fatal_error(error, cfg%path//': &design: max_tests and top must be >= 1')
         return
      end if
      if (.not. (ci_target > 0.0_dp) .or. .not. (prior_decades > 0.0_dp)) then
         call fatal_error(error, cfg%path//': &design: ci_target and prior_decades must be > 0')
         return
      end if
      cfg%design%noise = noise
      cfg%design%max_tests = max_tests
      cfg%design%ci_target = ci_target
      cfg%design%prior_decades = prior_decades
      cfg%design%top = top
   end subroutine read_design

   subroutine read_tests(unit, cfg, error)
      integer, intent(in) :: unit
      type(run_config), intent(inout) :: cfg
      type(error_type), allocatable, intent(out) :: error
      ! Variables of the &test group (see the README's namelist reference)
      character(len=name_len) :: name, history, file, control, data_file, time_column, &
                                 stress_column, strain_column, weight_column, data_unit, &
                                 filter_column, data_format, weighting, backend, output_file, &
                                 output_format, output_time, output_stress, output_unit, &
                                 constants_file, constants_format
      character(len=2048) :: command
      character(len=128) :: filter(max_list)
      real(dp) :: dt_out, amp_first, amp_last, quarter_time, levels(max_list), ramp_time, &
                  holds(max_list), up, down, seg_time, strain_range, mean_strain, strain_rate, &
                  period, hold_max, hold_min, final_strain, stress, duration, noise, sig, &
                  time_limit, rates(max_list)
      logical :: candidate
      integer :: npeaks, repeats, cycles, seed, ios, ntest
      character(len=512) :: msg
      type(test_config), allocatable :: tests(:)
      type(test_config) :: tc
      character(len=:), allocatable :: where
      namelist /test/ name, history, dt_out, amp_first, amp_last, npeaks, quarter_time, levels, &
         ramp_time, holds, up, down, repeats, seg_time, strain_range, mean_strain, strain_rate, &
         period, cycles, hold_max, hold_min, final_strain, stress, duration, file, control, &
         data_file, time_column, stress_column, strain_column, weight_column, data_unit, &
         filter_column, filter, data_format, weighting, sig, noise, seed, backend, command, &
         output_file, output_format, output_time, output_stress, output_unit, constants_file, &
         constants_format, time_limit, candidate, rates

      allocate (tests(0))
      rewind (unit)
      ntest = 0
      do
         call set_defaults()
         read (unit, nml=test, iostat=ios, iomsg=msg)
         if (is_iostat_end(ios)) exit
         ntest = ntest + 1
         where = cfg%path//': &test #'//str(ntest)
         if (len_trim(name) > 0) where = where//" '"//trim(name)//"'"
         where = where//': '
         if (ios /= 0) then
            call fatal_error(error, where//trim(msg)//' (iostat '//str(ios)//')')
            return
         end if
         call build_test(tc, error)
         if (allocated(error)) then
            call prefix_error(error, where)
            return
         end if
         call append_test(tests, tc)
      end do
      if (ntest == 0) then
         call fatal_error(error, cfg%path//': no &test group: at least one test is needed')
         return
      end if
      call move_alloc(tests, cfg%tests)

   contains

      subroutine set_defaults()
         name = ''
         history = ''
         file = ''
         control = 'strain'
         data_file = ''
         time_column = 'time'
         stress_column = 'stress'
         strain_column = 'strain'
         weight_column = ''
         data_unit = ''
         filter_column = ''
         filter = ''
         data_format = ''
         weighting = 'none'
         dt_out = 1.0_dp
         amp_first = 0.0005_dp; amp_last = 0.005_dp; npeaks = 12; quarter_time = 10.0_dp
         levels = unset; holds = unset; ramp_time = 1.0_dp
         up = 0.0005_dp; down = 0.00025_dp; repeats = 15; seg_time = 40.0_dp
         strain_range = unset; mean_strain = 0.0_dp; strain_rate = 0.0_dp; period = 0.0_dp
         cycles = 1; hold_max = 0.0_dp; hold_min = 0.0_dp
         final_strain = unset; stress = unset; duration = unset
         noise = 0.0_dp; seed = 1; sig = 0.0_dp
         backend = 'internal'; command = ''; output_file = ''; output_format = 'prvar'
         output_time = 'TIME'; output_stress = 'STRESS'; output_unit = ''
         constants_file = 'Constants.txt'; constants_format = '(E12.5)'; time_limit = 3600.0_dp
         candidate = .false.; rates = unset
      end subroutine set_defaults

      subroutine build_test(t, error)
         type(test_config), intent(out) :: t
         type(error_type), allocatable, intent(out) :: error
         integer :: nlev, nhold
         if (len_trim(name) == 0) then
            call fatal_error(error, 'name is not set')
            return
         end if
         if (verify(trim(name), 'abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_-.') /= 0) then
            call fatal_error(error, "name = '"//trim(name)//"' may hold only letters, digits, _ - .")
            return
         end if
         t%name = trim(name)
         t%candidate = candidate
         t%history_kind = lower_text(trim(history))
         if (.not. (dt_out >= 0.0_dp)) then
            call fatal_error(error, 'dt_out must be >= 0 s')
            return
         end if
         t%dt_out = dt_out
         if (noise < 0.0_dp) then
            call fatal_error(error, 'noise must be >= 0')
            return
         end if
         t%noise = noise
         t%seed = seed
         t%sig = sig
         t%weighting = lower_text(trim(weighting))
         select case (t%weighting)
         case ('none', 'threshold', 'relaxation', 'column')
         case default
            call fatal_error(error, "weighting = '"//trim(weighting)// &
               "' is not known (none, threshold, relaxation, column)")
            return
         end select
         if (t%weighting == 'column' .and. len_trim(weight_column) == 0) then
            call fatal_error(error, "weighting = 'column' needs weight_column")
            return
         end if
         t%has_data = len_trim(data_file) > 0
         t%data%file = resolve_path(cfg%base_dir, trim(data_file))
         t%data%time_col = trim(time_column)
         t%data%stress_col = trim(stress_column)
         t%data%strain_col = trim(strain_column)
         t%data%weight_col = trim(weight_column)
         t%data%unit = trim(data_unit)
         if (len_trim(data_unit) == 0) t%data%unit = cfg%units
         if (lower_text(t%data%unit) == 'mpa') t%data%unit = 'MPa'
         if (t%data%unit /= 'ksi' .and. t%data%unit /= 'MPa') then
            call fatal_error(error, "data_unit = '"//trim(data_unit)//"' is not known (ksi or MPa)")
            return
         end if
         t%data%filter_col = trim(filter_column)
         t%data%filter_values = pack(filter, len_trim(filter) > 0)
         t%data%format = trim(data_format)
         call build_external(t%name, t%ext, error)
         if (allocated(error)) return
         nlev = count(levels /= unset)
         nhold = count(holds /= unset)
         select case (t%history_kind)
         case ('thesis_lcf')
            call thesis_lcf_history(amp_first, amp_last, npeaks, quarter_time, t%hist, error)
         case ('relaxation')
            if (nlev == 0) then
               levels(1:2) = [0.00075_dp, 0.001_dp]
               nlev = 2
            end if
            if (nhold == 0) then
               holds(1:nlev) = 600.0_dp
               nhold = nlev
            end if
            call relaxation_history(levels(:nlev), ramp_time, holds(:nhold), t%hist, error)
         case ('ratchet')
            call ratchet_history(up, down, repeats, seg_time, t%hist, error)
         case ('cyclic')
            if (strain_range == unset) then
               call fatal_error(error, "history 'cyclic' needs strain_range")
               return
            end if
            call cyclic_history(strain_range, mean_strain, strain_rate, period, cycles, &
                                hold_max, hold_min, t%hist, error)
         case ('tensile')
            if (final_strain == unset) then
               call fatal_error(error, "history 'tensile' needs final_strain")
               return
            end if
            call tensile_history(strain_rate, final_strain, t%hist, error)
         case ('rate_jump')
            if (final_strain == unset .or. count(rates /= unset) == 0) then
               call fatal_error(error, "history 'rate_jump' needs rates and final_strain")
               return
            end if
            call rate_jump_history(pack(rates, rates /= unset), final_strain, t%hist, error)
         case ('creep')
            if (stress == unset .or. duration == unset) then
               call fatal_error(error, "history 'creep' needs stress and duration")
               return
            end if
            call creep_history(stress, ramp_time, duration, t%hist, error)
         case ('file')
            call file_history(resolve_path(cfg%base_dir, trim(file)), lower_text(trim(control)), &
                              t%hist, error)
         case ('data')
            if (.not. t%has_data) then
               call fatal_error(error, "history 'data' needs data_file")
               return
            end if
            call data_history(t%data, t%hist, error)
         case ('')
            call fatal_error(error, 'history is not set (thesis_lcf, relaxation, ratchet, '// &
               'cyclic, tensile, rate_jump, creep, file, data)')
         case default
            call fatal_error(error, "history = '"//trim(history)//"' is not known (thesis_lcf, "// &
               'relaxation, ratchet, cyclic, tensile, rate_jump, creep, file, data)')
         end select
      end subroutine build_test

      !> The external backend's settings, checked
      subroutine build_external(test_name, ext, error)
         character(len=*), intent(in) :: test_name
         type(external_spec), intent(out) :: ext
         type(error_type), allocatable, intent(out) :: error
         character(len=64) :: probe
         integer :: ios
         select case (lower_text(trim(backend)))
         case ('internal')
            ext%enabled = .false.
         case ('external')
            ext%enabled = .true.
         case default
            call fatal_error(error, "backend = '"//trim(backend)//"' is not known (internal or external)")
            return
         end select
         ext%command = trim(command)
         ext%output_file = trim(output_file)
         if (len_trim(output_file) == 0) ext%output_file = test_name//'_prvar.txt'
         ext%output_format = lower_text(trim(output_format))
         ext%time_title = trim(output_time)
         ext%stress_title = trim(output_stress)
         ext%unit = trim(output_unit)
         if (len_trim(output_unit) == 0) ext%unit = cfg%units
         if (lower_text(ext%unit) == 'mpa') ext%unit = 'MPa'
         ext%constants_file = trim(constants_file)
         ext%constants_format = trim(constants_format)
         ext%time_limit = time_limit
         if (.not. ext%enabled) return
         if (len_trim(command) == 0) then
            call fatal_error(error, "backend = 'external' needs command")
         else if (len_trim(command) == len(command)) then
            call fatal_error(error, 'command is longer than '//str(len(command) - 1)//' characters')
         else if (ext%output_format /= 'prvar' .and. ext%output_format /= 'columns') then
            call fatal_error(error, "output_format = '"//trim(output_format)// &
               "' is not known (prvar or columns)")
         else if (ext%unit /= 'ksi' .and. ext%unit /= 'MPa') then
            call fatal_error(error, "output_unit = '"//trim(output_unit)//"' is not known (ksi or MPa)")
         else if (.not. (time_limit > 0.0_dp)) then
            call fatal_error(error, 'time_limit must be > 0 s')
         else if (len_trim(constants_file) == 0 .or. index(constants_file, '/') > 0) then
            call fatal_error(error, "constants_file = '"//trim(constants_file)// &
               "' must be a plain file name (it is written into the work folder)")
         else if (index(ext%output_file, '/') > 0 .or. index(ext%output_file, '..') > 0) then
            call fatal_error(error, "output_file = '"//ext%output_file// &
               "' must be a plain file name inside the work folder")
         end if
         if (allocated(error)) return
         write (probe, ext%constants_format, iostat=ios) 1.0_dp
         if (ios /= 0 .or. verify(ext%constants_format, '()0123456789.EeSsDdGg') /= 0) then
            call fatal_error(error, "constants_format = '"//ext%constants_format// &
               "' is not a Fortran format for one real such as (E12.5)")
         end if
      end subroutine build_external
   end subroutine read_tests

   !> Append by element-wise copies (array constructors of types with allocatable
   !> components are miscompiled by some gfortran versions)
   subroutine append_test(tests, tc)
      type(test_config), allocatable, intent(inout) :: tests(:)
      type(test_config), intent(in) :: tc
      type(test_config), allocatable :: tmp(:)
      integer :: k
      allocate (tmp(size(tests) + 1))
      do k = 1, size(tests)
         tmp(k) = tests(k)
      end do
      tmp(size(tests) + 1) = tc
      call move_alloc(tmp, tests)
   end subroutine append_test

   !> History from a file of (time, value) points; control is 'strain' or 'stress'
   subroutine file_history(path, control, hist, error)
      character(len=*), intent(in) :: path, control
      type(history_type), intent(out) :: hist
      type(error_type), allocatable, intent(out) :: error
      real(dp), allocatable :: vals(:, :)
      integer :: mode
      select case (control)
      case ('strain'); mode = control_strain
      case ('stress'); mode = control_stress
      case default
         call fatal_error(error, "control = '"//control//"' is not known (strain or stress)")
         return
      end select
      call read_columns(path, ['1', '2'], vals, error)
      if (allocated(error)) return
      call history_from_points(vals(:, 1), vals(:, 2), mode, hist, error)
      if (allocated(error)) call prefix_error(error, path//': ')
   end subroutine file_history

   !> Strain-controlled history from a measured file's time and strain columns
   subroutine data_history(spec, hist, error)
      type(data_spec), intent(in) :: spec
      type(history_type), intent(out) :: hist
      type(error_type), allocatable, intent(out) :: error
      real(dp), allocatable :: vals(:, :)
      integer :: nmerged
      character(len=128) :: cols(2)
      cols(1) = spec%time_col
      cols(2) = spec%strain_col
      call read_data_columns(spec, cols, vals, error)
      if (allocated(error)) return
      call merge_repeated_times(vals, spec%file, nmerged, error)
      if (allocated(error)) return
      call measured_history(vals(:, 1), vals(:, 2), control_strain, hist, error)
      if (allocated(error)) call prefix_error(error, spec%file//': ')
   end subroutine data_history

   !> Read columns of a data_spec's file with its filter and format
   subroutine read_data_columns(spec, columns, vals, error)
      type(data_spec), intent(in) :: spec
      character(len=*), intent(in) :: columns(:)
      real(dp), allocatable, intent(out) :: vals(:, :)
      type(error_type), allocatable, intent(out) :: error
      call read_columns(spec%file, columns, vals, error, spec%filter_col, spec%filter_values, &
                        spec%format)
   end subroutine read_data_columns

   !> Folder part of a path ('.' when none)
   pure function dirname(path) result(dir)
      character(len=*), intent(in) :: path
      character(len=:), allocatable :: dir
      integer :: k
      k = index(path, '/', back=.true.)
      if (k == 0) then
         dir = '.'
      else if (k == 1) then
         dir = '/'
      else
         dir = path(:k - 1)
      end if
   end function dirname

   !> A path relative to base unless absolute or empty; leading '../' steps are folded into
   !> base ('decks' + '../data/x' gives 'data/x')
   pure function resolve_path(base, path) result(full)
      character(len=*), intent(in) :: base, path
      character(len=:), allocatable :: full
      character(len=:), allocatable :: b, p
      if (len(path) == 0) then
         full = ''
         return
      else if (path(1:1) == '/') then
         full = path
         return
      end if
      b = base
      p = path
      do while (len(p) > 3 .and. b /= '.' .and. b /= '/')
         if (p(1:3) /= '../') exit
         if (b == '..' .or. index(b, '/..', back=.true.) == max(len(b) - 2, 1)) exit
         b = dirname(b)
         p = p(4:)
      end do
      if (b == '.') then
         full = p
      else if (b == '/') then
         full = '/'//p
      else
         full = b//'/'//p
      end if
   end function resolve_path

end module usharp_input
