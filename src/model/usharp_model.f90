!> What every part of usharp needs from a unified viscoplastic model, in one place: an
!> abstract type that each model extends (one module per model, registered in
!> usharp_model_registry). Drivers, the objective, the optimisers, identify, design, the
!> deck writer and the user-material adapters hold a class(model_type) and know no model by
!> name.
!>
!> A model provides
!> - its constants: count, names, units (the power of the stress unit in each), literature
!>   ranges (the default bounds and multi-start box), get and set by number, and its
!>   &constants namelist (read and written with the constants' own names);
!> - setup: checks of the constants and conditions, and what follows from them at the
!>   model's temperature (temperature enters only here: rates and updates see the set-up
!>   model, so a test at another temperature is the model set up again);
!> - the uniaxial form: its state (the first component is the inelastic strain), the virgin
!>   state, the rates with their analytic Jacobian (RODAS4 and CVODE), which states are
!>   stresses (absolute tolerances) and the back stress and drag stress the outputs report;
!> - the 3-D form: its state (Mandel vectors), the virgin state and the implicit J2 stress
!>   update over an increment with its consistent tangent (the single-element driver and
!>   the UMAT / USERMAT adapters);
!> - the FE property list of its drop-in user material.
!>
!> Units: stresses in the model's unit (ksi or MPa), time in s, temperature in K.
module usharp_model
   use usharp_kinds, only: dp
   use usharp_error, only: error_type, fatal_error
   use usharp_strings, only: lower
   use usharp_effect_values, only: test_effects
   implicit none
   private

   public :: model_type, constant_index, constant_names, elastic_moduli, model_at, wrapped_rates
   public :: update_status_ok, update_status_cut, block_scalar, block_strain, block_stress

   !> Kinds of block in the FE state layout: a scalar, or a 6-component strain or stress
   !> tensor (engineering shear strain, tensor shear stress in the code's order)
   integer, parameter :: block_scalar = 0, block_strain = 1, block_stress = 2

   !> Outcome of a 3-D stress update: converged, or the caller must retry with a smaller
   !> increment
   integer, parameter :: update_status_ok = 0, update_status_cut = 1

   !> A unified viscoplastic model at one temperature. The components are what every model
   !> has; a model's constants and derived quantities live in its extension.
   type, abstract :: model_type
      real(dp) :: temperature = 866.15_dp  !< K
      real(dp) :: tm = 1800.0_dp           !< melting temperature, K
      real(dp) :: youngs = 22.5e3_dp       !< Young's modulus, model stress unit
      real(dp) :: poisson = 0.3_dp         !< Poisson's ratio
   contains
      !> The model's name as &model name gives it (lower case)
      procedure(name_fn), deferred :: name
      !> Number of constants
      procedure(count_fn), deferred :: n_constants
      !> Name of constant i (as logs and reports print it)
      procedure(constant_name_fn), deferred :: constant_name
      !> Power of the stress unit in the unit of constant i (1/ksi: -1)
      procedure(power_fn), deferred :: stress_power
      !> Literature range of constant i in the stress unit literature_units gives
      procedure(range_sub), deferred :: literature_range
      !> Stress unit of the literature ranges (ksi or MPa)
      procedure(name_fn), deferred :: literature_units
      !> Constant i
      procedure(get_fn), deferred :: get_constant
      !> Set constant i (setup must follow before the model is used)
      procedure(set_sub), deferred :: set_constant
      !> The &constants namelist: read from text (constants not given keep the value unset)
      !> or written to unit
      procedure(namelist_sub), deferred :: constants_namelist
      !> Check constants and conditions and derive what depends on them and on temperature
      procedure(setup_sub), deferred :: setup
      !> Number of uniaxial states (the first is the inelastic strain)
      procedure(count_fn), deferred :: n_uniaxial
      !> The virgin uniaxial state
      procedure(initial_sub), deferred :: uniaxial_initial
      !> Whether uniaxial state i is a stress (absolute tolerance scaled by E) or a strain
      procedure(is_stress_fn), deferred :: uniaxial_is_stress
      !> The uniaxial states that must stay positive (the rates are defined there only);
      !> integrators shorten a step that leaves them
      procedure(positive_fn), deferred :: positive_states
      !> Uniaxial rates and their Jacobian
      procedure(rates_sub), deferred :: uniaxial_rates
      !> Back stress and drag stress the outputs report for a uniaxial state
      procedure(outputs_sub), deferred :: uniaxial_outputs
      !> Number of 3-D states
      procedure(count_fn), deferred :: n_state
      !> The virgin 3-D state
      procedure(initial_sub), deferred :: state_initial
      !> Implicit J2 stress update with its consistent tangent
      procedure(update_sub), deferred :: stress_update
      !> Substeps the update takes per increment when it needs no more (nsub of an easy one)
      procedure(count_fn), deferred :: update_substeps
      !> Inelastic strain, back stress and drag stress in the 11 direction of a 3-D state
      !> under uniaxial stress in 11, as the outputs report them
      procedure(state_outputs_sub), deferred :: state_outputs
      !> Number of properties of the drop-in user material
      procedure(count_fn), deferred :: n_props
      !> Name of property i
      procedure(constant_name_fn), deferred :: prop_name
      !> The property list of the model
      procedure(props_sub), deferred :: to_props
      !> The model from a property list at temperature temp (K), set up; message is empty when
      !> the properties can be used, else one line naming the offending property
      procedure(from_props_sub), deferred :: from_props
      !> Layout of the FE state variables: block b of the 3-D state starts at y(y_first(b)),
      !> is stored from statev(code_first(b)) and is of kind(b) (block_scalar, _strain, _stress)
      procedure(layout_sub), deferred :: fe_layout
      !> State variables an FE code must start from other than zero (the external backend
      !> writes them after the properties, an APDL deck sets them by TB,STATE): their
      !> positions in statev, values, short names and descriptions
      procedure :: fe_start_values
      !> A 3-D state read from an FE code's state variables, which start as zeros: its unset
      !> parts take their virgin values
      procedure(complete_sub), deferred :: complete_state
      !> Derivative of the uniaxial rates in constant i by central differences, with what
      !> depends on temperature kept (forward sensitivities); a model may do it faster
      procedure :: rates_constant_derivative
      !> The stress unit (ksi or MPa) of the constants: defaults that depend on it follow
      procedure :: set_units
      !> A setting of the model's own in &model (name, value); an error when it has none
      procedure :: set_option
      !> Stresses the set-up model derived that outputs report (name and value, model unit)
      procedure :: derived_values
      !> The set-up model moved to another temperature during a test (a thermomechanical
      !> history): the rates follow the temperature, the initial state stays that of the
      !> temperature the model was set up at
      procedure :: set_temperature
      !> Whether the rates depend on the temperature (a test at a temperature of its own, or
      !> a temperature cycle, then changes them): by default they do
      procedure :: temperature_matters
      !> Whether the effects of usharp diagnose on states of the model's own act on it (an
      !> initial back stress R0 and drag offset dD0, specimen scatter's factor on the initial
      !> drag, a softened drag): only a model that applies them in extended_rates and
      !> extended_initial; by default they do not (wrapped_rates)
      procedure :: own_state_effects
      !> The rates of the model with the effects of usharp diagnose (its states, then the
      !> accumulated inelastic strain p and a second back stress R2): by default its own rates
      !> wrapped (wrapped_rates); a model whose states the effects also act on overrides it
      procedure :: extended_rates => model_extended_rates
      !> The extended start: by default the model's virgin state, p = R2 = 0
      procedure :: extended_initial => model_extended_initial
   end type model_type

   abstract interface
      pure function name_fn(self) result(name)
         import :: model_type
         class(model_type), intent(in) :: self
         character(len=:), allocatable :: name
      end function name_fn

      pure integer function count_fn(self) result(n)
         import :: model_type
         class(model_type), intent(in) :: self
      end function count_fn

      pure function constant_name_fn(self, i) result(name)
         import :: model_type
         class(model_type), intent(in) :: self
         integer, intent(in) :: i
         character(len=:), allocatable :: name
      end function constant_name_fn

      pure integer function power_fn(self, i) result(p)
         import :: model_type
         class(model_type), intent(in) :: self
         integer, intent(in) :: i
      end function power_fn

      pure subroutine range_sub(self, i, low, high)
         import :: model_type, dp
         class(model_type), intent(in) :: self
         integer, intent(in) :: i
         real(dp), intent(out) :: low, high
      end subroutine range_sub

      pure real(dp) function get_fn(self, i) result(val)
         import :: model_type, dp
         class(model_type), intent(in) :: self
         integer, intent(in) :: i
      end function get_fn

      pure subroutine set_sub(self, i, val)
         import :: model_type, dp
         class(model_type), intent(inout) :: self
         integer, intent(in) :: i
         real(dp), intent(in) :: val
      end subroutine set_sub

      !> With text: every constant is set to unset, then read; with unit: written
      subroutine namelist_sub(self, unset, ios, msg, text, unit)
         import :: model_type, dp
         class(model_type), intent(inout) :: self
         real(dp), intent(in) :: unset
         integer, intent(out) :: ios
         character(len=*), intent(out) :: msg
         character(len=*), intent(in), optional :: text(:)
         integer, intent(in), optional :: unit
      end subroutine namelist_sub

      pure subroutine setup_sub(self, error)
         import :: model_type, error_type
         class(model_type), intent(inout) :: self
         type(error_type), allocatable, intent(out) :: error
      end subroutine setup_sub

      pure subroutine initial_sub(self, y)
         import :: model_type, dp
         class(model_type), intent(in) :: self
         real(dp), intent(out) :: y(:)
      end subroutine initial_sub

      pure logical function is_stress_fn(self, i) result(is_stress)
         import :: model_type
         class(model_type), intent(in) :: self
         integer, intent(in) :: i
      end function is_stress_fn

      pure function positive_fn(self) result(idx)
         import :: model_type
         class(model_type), intent(in) :: self
         integer, allocatable :: idx(:)
      end function positive_fn

      !> Rates ydot of the state y at stress sigma and, if asked, jac(i, j) = d ydot_i / d y_j
      !> where sigma depends on the inelastic strain y(1) through dsig_depsin (-E under strain
      !> control, 0 under stress control). The values are the same with and without jac.
      pure subroutine rates_sub(self, sigma, dsig_depsin, y, ydot, jac)
         import :: model_type, dp
         class(model_type), intent(in) :: self
         real(dp), intent(in) :: sigma, dsig_depsin
         real(dp), intent(in), contiguous :: y(:)
         real(dp), intent(out), contiguous :: ydot(:)
         real(dp), intent(out), optional, contiguous :: jac(:, :)
      end subroutine rates_sub

      pure subroutine outputs_sub(self, y, back, drag)
         import :: model_type, dp
         class(model_type), intent(in) :: self
         real(dp), intent(in) :: y(:)
         real(dp), intent(out) :: back, drag
      end subroutine outputs_sub

      !> Stress update over one increment: eps0 the strain at its start, deps its increment
      !> (Mandel: 11, 22, 33, sqrt2*12, sqrt2*23, sqrt2*13), dt the time step (s), y0 the
      !> state at the start. On success status = update_status_ok with sigma, y and the
      !> consistent tangent ddsde = d sigma / d eps; otherwise update_status_cut (the caller
      !> retries smaller). nsub returns the substeps used, nsubsteps asks for a number.
      pure subroutine update_sub(self, eps0, deps, dt, y0, sigma, y, ddsde, status, nsub, nsubsteps)
         import :: model_type, dp
         class(model_type), intent(in) :: self
         real(dp), intent(in) :: eps0(6), deps(6), dt, y0(:)
         real(dp), intent(out) :: sigma(6), y(:), ddsde(6, 6)
         integer, intent(out) :: status, nsub
         integer, intent(in), optional :: nsubsteps
      end subroutine update_sub

      pure subroutine state_outputs_sub(self, y, eps_in, back, drag)
         import :: model_type, dp
         class(model_type), intent(in) :: self
         real(dp), intent(in) :: y(:)
         real(dp), intent(out) :: eps_in, back, drag
      end subroutine state_outputs_sub

      pure subroutine props_sub(self, props)
         import :: model_type, dp
         class(model_type), intent(in) :: self
         real(dp), intent(out) :: props(:)
      end subroutine props_sub

      pure subroutine from_props_sub(self, props, temp, message)
         import :: model_type, dp
         class(model_type), intent(inout) :: self
         real(dp), intent(in) :: props(:), temp
         character(len=*), intent(out) :: message
      end subroutine from_props_sub

      pure subroutine layout_sub(self, y_first, code_first, kind)
         import :: model_type
         class(model_type), intent(in) :: self
         integer, allocatable, intent(out) :: y_first(:), code_first(:), kind(:)
      end subroutine layout_sub

      pure subroutine complete_sub(self, y)
         import :: model_type, dp
         class(model_type), intent(in) :: self
         real(dp), intent(inout) :: y(:)
      end subroutine complete_sub
   end interface

contains

   !> d ydot / d c_i by central differences (relative step 1e-6) of models with constant i
   !> changed and set up again: what depends on temperature follows the constant
   pure subroutine rates_constant_derivative(self, i, sigma, dsig_depsin, y, dfdc)
      class(model_type), intent(in) :: self
      integer, intent(in) :: i
      real(dp), intent(in) :: sigma, dsig_depsin
      real(dp), intent(in), contiguous :: y(:)
      real(dp), intent(out) :: dfdc(:)
      class(model_type), allocatable :: mp, mm
      type(error_type), allocatable :: error
      real(dp) :: c, h, fp(size(y)), fm(size(y))
      c = self%get_constant(i)
      h = 1.0e-6_dp*abs(c)
      allocate (mp, source=self)
      allocate (mm, source=self)
      call mp%set_constant(i, c + h)
      call mm%set_constant(i, c - h)
      call mp%setup(error)
      if (.not. allocated(error)) call mm%setup(error)
      if (allocated(error)) then
         dfdc = 0.0_dp
         return
      end if
      call mp%uniaxial_rates(sigma, dsig_depsin, y, fp)
      call mm%uniaxial_rates(sigma, dsig_depsin, y, fm)
      dfdc = (fp - fm)/(2.0_dp*h)
   end subroutine rates_constant_derivative

   !> No defaults depend on the unit
   pure subroutine set_units(self, units)
      class(model_type), intent(inout) :: self
      character(len=*), intent(in) :: units
   end subroutine set_units

   !> No settings of its own
   pure subroutine set_option(self, name, val, error)
      class(model_type), intent(inout) :: self
      character(len=*), intent(in) :: name
      real(dp), intent(in) :: val
      type(error_type), allocatable, intent(out) :: error
      call fatal_error(error, name//' is not a setting of the '//self%name()//' model')
   end subroutine set_option

   !> Every state variable starts at zero
   pure subroutine fe_start_values(self, pos, vals, names, notes)
      class(model_type), intent(in) :: self
      integer, allocatable, intent(out) :: pos(:)
      real(dp), allocatable, intent(out) :: vals(:)
      character(len=:), allocatable, intent(out) :: names(:), notes(:)
      allocate (pos(0), vals(0))
      allocate (character(len=1) :: names(0), notes(0))
   end subroutine fe_start_values

   !> Nothing derived to report
   pure subroutine derived_values(self, names, vals)
      class(model_type), intent(in) :: self
      character(len=:), allocatable, intent(out) :: names(:)
      real(dp), allocatable, intent(out) :: vals(:)
      allocate (character(len=1) :: names(0))
      allocate (vals(0))
   end subroutine derived_values

   !> Any model: set up again at the new temperature (what only the initial state uses is
   !> derived again too, and then not used)
   pure subroutine set_temperature(self, temperature, error)
      class(model_type), intent(inout) :: self
      !> K
      real(dp), intent(in) :: temperature
      type(error_type), allocatable, intent(out) :: error
      self%temperature = temperature
      call self%setup(error)
   end subroutine set_temperature

   !> By default a model's rates follow the temperature
   pure logical function temperature_matters(self)
      class(model_type), intent(in) :: self
      temperature_matters = .true.
   end function temperature_matters

   pure logical function own_state_effects(self)
      class(model_type), intent(in) :: self
      own_state_effects = .false.
   end function own_state_effects

   !> Any model's rates with the effects: wrapped_rates
   pure subroutine model_extended_rates(self, eff, sigma, y, ydot, dsig_depsin, jac)
      class(model_type), intent(in) :: self
      type(test_effects), intent(in) :: eff
      real(dp), intent(in) :: sigma
      real(dp), intent(in), contiguous :: y(:)
      real(dp), intent(out), contiguous :: ydot(:)
      real(dp), intent(in), optional :: dsig_depsin
      real(dp), intent(out), optional, contiguous :: jac(:, :)
      call wrapped_rates(self, eff, sigma, y, ydot, dsig_depsin, jac)
   end subroutine model_extended_rates

   !> The model's virgin state, then p = R2 = 0
   pure subroutine model_extended_initial(self, eff, y)
      class(model_type), intent(in) :: self
      type(test_effects), intent(in) :: eff
      real(dp), intent(out) :: y(:)
      y = 0.0_dp
      call self%uniaxial_initial(y(1:size(y) - 2))
   end subroutine model_extended_initial

   !> Any model's rates wrapped: its states y(1:m) driven by sigma - R2 (its rates depend on
   !> eps_in only through sigma), then
   !> dp/dt = |deps_in/dt| and dR2/dt = H3 deps_in/dt - gamma3 R2 dp/dt. The effects on states
   !> of a model's own (Miller: the softened drag, R0 and the drag offsets) do not apply.
   pure subroutine wrapped_rates(model, eff, sigma, y, ydot, dsig_depsin, jac)
      class(model_type), intent(in) :: model
      type(test_effects), intent(in) :: eff
      real(dp), intent(in) :: sigma
      real(dp), intent(in), contiguous :: y(:)
      real(dp), intent(out), contiguous :: ydot(:)
      real(dp), intent(in), optional :: dsig_depsin
      real(dp), intent(out), optional, contiguous :: jac(:, :)
      real(dp) :: sg, dfdy(size(y)), dfds(size(y) - 2), jm(size(y) - 2, size(y) - 2)
      integer :: m, np, nr
      m = size(y) - 2
      np = m + 1
      nr = m + 2
      if (present(jac)) then
         ! The rates depend on eps_in only through sigma: with d sigma/d eps_in = 1 the first
         ! column of the model's Jacobian is d ydot/d sigma; d sigma_eff/d R2 = -1
         ! The model's Jacobian in an array of its own: jac(1:m, 1:m) is not contiguous
         call model%uniaxial_rates(sigma - y(nr), 1.0_dp, y(1:m), ydot(1:m), jm)
         jac = 0.0_dp
         jac(1:m, 1:m) = jm
         dfds = jm(:, 1)
         jac(1:m, 1) = dfds*dsig_depsin
         jac(1:m, nr) = -dfds
      else
         call model%uniaxial_rates(sigma - y(nr), 0.0_dp, y(1:m), ydot(1:m))
      end if
      ydot(np) = abs(ydot(1))
      ydot(nr) = eff%h3*ydot(1) - eff%gamma3*y(nr)*ydot(np)
      if (.not. present(jac)) return
      sg = sign(1.0_dp, ydot(1))
      dfdy = sg*jac(1, :)
      jac(np, :) = dfdy
      jac(nr, :) = eff%h3*jac(1, :) - eff%gamma3*y(nr)*dfdy
      jac(nr, nr) = jac(nr, nr) - eff%gamma3*ydot(np)
   end subroutine wrapped_rates

   !> A copy of model at another temperature (K), set up there: what depends on temperature
   !> follows (the Miller model's B*theta and D0)
   subroutine model_at(model, temperature, out, error)
      class(model_type), intent(in) :: model
      real(dp), intent(in) :: temperature
      class(model_type), allocatable, intent(out) :: out
      type(error_type), allocatable, intent(out) :: error
      allocate (out, source=model)
      out%temperature = temperature
      call out%setup(error)
   end subroutine model_at

   !> Index of a constant by its (case-insensitive) name, 0 if the model has none of that name
   pure integer function constant_index(model, name) result(idx)
      class(model_type), intent(in) :: model
      character(len=*), intent(in) :: name
      integer :: i
      idx = 0
      do i = 1, model%n_constants()
         if (lower(trim(adjustl(name))) == lower(model%constant_name(i))) idx = i
      end do
   end function constant_index

   !> Names of the constants with indices idx (blank-padded to the longest)
   pure function constant_names(model, idx) result(names)
      class(model_type), intent(in) :: model
      integer, intent(in) :: idx(:)
      character(len=:), allocatable :: names(:)
      integer :: j, w
      w = 1
      do j = 1, size(idx)
         w = max(w, len(model%constant_name(idx(j))))
      end do
      allocate (character(len=w) :: names(size(idx)))
      do j = 1, size(idx)
         names(j) = model%constant_name(idx(j))
      end do
   end function constant_names

   !> Shear and bulk moduli from E and Poisson's ratio
   elemental subroutine elastic_moduli(youngs, poisson, g, k)
      real(dp), intent(in) :: youngs, poisson
      real(dp), intent(out) :: g, k
      g = youngs/(2.0_dp*(1.0_dp + poisson))
      k = youngs/(3.0_dp*(1.0_dp - 2.0_dp*poisson))
   end subroutine elastic_moduli
end module usharp_model
