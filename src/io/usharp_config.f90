!> The contents of a usharp input file after reading and checking: one run_config holding the
!> settings of every group. Each group's type lives in its reader (usharp_input_<group>) and is
!> re-exported here.
module usharp_config
   use usharp_model, only: model_type
   use usharp_simulation, only: solver_options
   use usharp_input_fit, only: fit_config
   use usharp_input_design, only: design_config
   use usharp_input_diagnose, only: diagnose_config
   use usharp_input_test, only: test_config, data_spec, external_spec, test_increments
   implicit none
   private

   public :: run_config, test_config, test_increments, data_spec, fit_config, external_spec, design_config, diagnose_config

   !> Everything one input file holds
   type :: run_config
      character(len=:), allocatable :: path      !< the namelist file
      character(len=:), allocatable :: base_dir  !< its folder, for relative paths
      character(len=:), allocatable :: out_dir   !< &output
      character(len=:), allocatable :: units     !< &model: model stress unit, ksi or MPa
      class(model_type), allocatable :: model    !< &model and &constants
      type(solver_options) :: solver             !< &solver
      type(fit_config) :: fit                    !< &fit
      type(design_config) :: design              !< &design
      type(diagnose_config) :: diagnose          !< &diagnose
      type(test_config), allocatable :: tests(:) !< &test, in file order
   end type run_config
end module usharp_config
