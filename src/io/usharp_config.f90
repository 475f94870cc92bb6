!> The contents of a usharp input namelist file after reading and checking
module usharp_config
   use usharp_kinds, only: dp
   use usharp_miller, only: miller_model, n_constants
   use usharp_history, only: history_type
   use usharp_simulation, only: solver_options
   implicit none
   private

   public :: run_config, test_config, data_spec, fit_config, external_spec, design_config, diagnose_config, max_list

   !> Longest list in a namelist array variable (levels, holds, fit, filter values)
   integer, parameter :: max_list = 64

   !> Where a test's measured data come from and how to read them
   type :: data_spec
      character(len=:), allocatable :: file         !< path (relative to the namelist file)
      character(len=:), allocatable :: time_col     !< column name or position
      character(len=:), allocatable :: stress_col
      character(len=:), allocatable :: strain_col
      character(len=:), allocatable :: weight_col   !< optional user weight column
      character(len=:), allocatable :: unit         !< stress unit of the file: ksi or MPa
      character(len=:), allocatable :: filter_col   !< optional row filter column
      character(len=128), allocatable :: filter_values(:)
      character(len=:), allocatable :: format       !< optional Fortran format for fixed files
   end type data_spec

   !> How a test is simulated by an external program (an FE code in batch mode) instead of
   !> the internal integrator: the command, what it writes, and the constants file it reads
   type :: external_spec
      logical :: enabled = .false.                     !< backend = 'external'
      character(len=:), allocatable :: command         !< shell command, placeholders {work} ...
      character(len=:), allocatable :: output_file     !< written by the command in its work folder
      character(len=:), allocatable :: output_format   !< prvar or columns
      character(len=:), allocatable :: time_title      !< column title (or position) of time, s
      character(len=:), allocatable :: stress_title    !< column title (or position) of stress
      character(len=:), allocatable :: unit            !< stress unit of the output: ksi or MPa
      character(len=:), allocatable :: constants_file  !< name of the constants file in the work folder
      character(len=:), allocatable :: constants_format !< Fortran format of one constant, (E12.5)
      real(dp) :: time_limit = 3600.0_dp               !< s, then the command is killed
   end type external_spec

   !> One test: its load history, output interval and (for fits) its data and weighting
   type :: test_config
      character(len=:), allocatable :: name
      character(len=:), allocatable :: history_kind
      type(history_type) :: hist
      real(dp) :: dt_out = 1.0_dp           !< output interval, s
      real(dp) :: noise = 0.0_dp            !< relative Gaussian noise on stress (synthetic data)
      integer :: seed = 1                   !< noise seed
      logical :: has_data = .false.
      type(data_spec) :: data
      character(len=:), allocatable :: weighting  !< threshold, relaxation, none, column
      real(dp) :: sig = 0.0_dp              !< threshold stress for 'threshold' weighting
      type(external_spec) :: ext            !< external backend (when ext%enabled)
      logical :: candidate = .false.        !< a candidate test of `usharp design`
   end type test_config

   !> Test-matrix design settings (&design group)
   type :: design_config
      real(dp) :: noise = 0.01_dp     !< sd of the stress data as a fraction of the peak |stress|
      integer :: max_tests = 3        !< largest test matrix (current tests + candidates)
      real(dp) :: ci_target = 0.02_dp !< determined: 95 % interval within this fraction
      real(dp) :: prior_decades = 2.0_dp !< prior sd of log10 c, keeps log det finite
      integer :: top = 10             !< combinations listed
   end type design_config

   !> Diagnosis settings (&diagnose group); names are resolved by the diagnose command
   type :: diagnose_config
      character(len=64) :: holdout(max_list) = ''  !< tests held out of the fit
      character(len=16) :: effects(max_list) = ''  !< effects considered (none given: all)
      character(len=16) :: rows(max_list) = ''     !< self-check rows: injected effects, 'none' clean
      integer :: n_refit = 3                       !< leading candidates refitted
      integer :: refit_starts = 1                  !< screening end points each refit starts from
      integer :: global_starts = 4                 !< Latin-hypercube starts of the constants (baseline and refits)
                                                   !< when no local refit reaches the noise level
      logical :: cross_starts = .true.             !< a refit ending above another reruns from its constants
      real(dp) :: dlnE_dT = -4.0e-4_dp             !< 1/K, temperature slope of ln E
      real(dp) :: gamma3 = 200.0_dp                !< -, second back stress recovery (screening)
      real(dp) :: confirm_shrink = 0.5_dp          !< held-out structured gap removed to confirm
      integer :: reps = 10                         !< self-check repetitions per effect
      integer :: seed = 1                          !< self-check seed
      real(dp) :: noise = 0.01_dp                  !< self-check noise, fraction of the peak
      !> Per-specimen mode: the test diagnosed against the others (its replicates), 'all' for
      !> each test in turn; blank: the diagnosis of the fit
      character(len=64) :: specimen = ''
   end type diagnose_config

   !> Fit settings (&fit group)
   type :: fit_config
      logical :: fitted(n_constants) = .false.     !< which constants are searched
      character(len=:), allocatable :: method      !< hooke-jeeves
      character(len=:), allocatable :: objective   !< eq7 or eq13
      real(dp) :: rho = 0.5_dp
      real(dp) :: eps = 1.0e-6_dp
      integer :: itermax = 1000
      integer :: max_evals = 100000
      integer :: max_failures = 100                !< failures in a row before the fit aborts
      logical :: log_search = .false.
      !> Search bounds (physical units); lm, nelder-mead, anneal and multistart keep to them
      real(dp) :: lower(n_constants) = 0.0_dp, upper(n_constants) = 0.0_dp
      !> Box of the multi-start points (physical units)
      real(dp) :: box_lower(n_constants) = 0.0_dp, box_upper(n_constants) = 0.0_dp
      integer :: multistart = 0                    !< number of Latin-hypercube starts (0: none)
      integer :: seed = 1                          !< seed of multi-start and annealing
      real(dp) :: fd_step = 1.0e-3_dp              !< forward-difference step in log10 of a constant
      !> Jacobian of Levenberg-Marquardt: 'difference' (forward differences, one simulation
      !> per constant) or 'sensitivity' (CVODES forward sensitivities, one simulation)
      character(len=16) :: jacobian = 'difference'
      real(dp) :: anneal_t0 = 0.0_dp               !< initial temperature (0: the start objective)
      real(dp) :: anneal_rt = 0.85_dp              !< temperature reduction factor
      logical :: identify = .true.                 !< identifiability report after the fit
   end type fit_config

   !> Everything one input file holds
   type :: run_config
      character(len=:), allocatable :: path      !< the namelist file
      character(len=:), allocatable :: base_dir  !< its folder, for relative paths
      character(len=:), allocatable :: out_dir
      character(len=:), allocatable :: units     !< model stress unit: ksi or MPa
      type(miller_model) :: model
      type(solver_options) :: solver
      type(fit_config) :: fit
      type(design_config) :: design
      type(diagnose_config) :: diagnose
      type(test_config), allocatable :: tests(:)
   end type run_config
end module usharp_config
