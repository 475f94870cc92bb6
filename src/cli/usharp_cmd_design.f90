!> `usharp design`: rank candidate tests by how much each improves the determination of the
!> &fit constants at known constants (the input's &constants), written to <out_dir>/design.txt
module usharp_cmd_design
   use usharp_error, only: error_type
   use usharp_config, only: run_config
   use usharp_input, only: read_config_as
   use usharp_design, only: design_result, design_run, design_report
   use usharp_filesys, only: make_dir, join_path
   use usharp_output, only: write_lines
   implicit none
   private

   public :: design_command

contains

   subroutine design_command(path, out_dir, constants_file, lines, error)
      character(len=*), intent(in) :: path, out_dir, constants_file
      character(len=200), allocatable, intent(out) :: lines(:)
      type(error_type), allocatable, intent(out) :: error
      type(run_config) :: cfg
      type(design_result) :: res
      call read_config_as(path, constants_file, out_dir, cfg, error)
      if (allocated(error)) return
      call design_run(cfg, res, error)
      if (allocated(error)) return
      lines = design_report(res)
      call make_dir(cfg%out_dir, error)
      if (allocated(error)) return
      call write_lines(join_path(cfg%out_dir, 'design.txt'), lines, error)
   end subroutine design_command

end module usharp_cmd_design
