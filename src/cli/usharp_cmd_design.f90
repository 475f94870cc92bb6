!> `usharp design`: rank candidate tests by how much each improves the determination of the
!> &fit constants at known constants (the input's &constants), written to <out_dir>/design.txt
module usharp_cmd_design
   use usharp_error, only: error_type
   use usharp_config, only: run_config
   use usharp_input, only: read_config_as, check_inputs_kept
   use usharp_design, only: design_result, design_run, design_report, design_mark
   use usharp_filesys, only: join_path, unlock_file
   use usharp_output, only: write_lines
   use usharp_mpi, only: is_root
   use usharp_strings, only: report_line_len
   use usharp_overwrite, only: check_overwrite, take_folder
   implicit none
   private

   public :: design_command

contains

   !> The design of path's tests; every test's information is kept in
   !> <out_dir>/design.journal (mode: see run_tasks)
   subroutine design_command(path, out_dir, constants_file, lines, error, mode)
      character(len=*), intent(in) :: path, out_dir, constants_file, mode
      character(len=report_line_len), allocatable, intent(out) :: lines(:)
      type(error_type), allocatable, intent(out) :: error
      type(run_config) :: cfg
      type(design_result) :: res
      integer :: lock
      call read_config_as(path, constants_file, out_dir, cfg, error)
      if (allocated(error)) return
      call check_inputs_kept(cfg, path, constants_file, [character(len=14) :: 'design.txt', &
                             'design.journal'], [character(len=1) ::], error)
      if (allocated(error)) return
      ! A design.txt of the user's is refused before any work; an earlier design's (--resume
      ! too) is replaced
      call check_overwrite(cfg%out_dir, ['design.txt'], [design_mark], 'design', mode == 'force', error)
      if (allocated(error)) return
      ! Held for the design: a second design (or run) into the folder is refused
      call take_folder(cfg%out_dir, lock, error)
      if (allocated(error)) return
      call design_run(cfg, res, error, join_path(cfg%out_dir, 'design.journal'), mode, constants_file)
      if (.not. allocated(error) .and. is_root()) then
         lines = design_report(res)
         call write_lines(join_path(cfg%out_dir, 'design.txt'), lines, error)
      end if
      call unlock_file(lock)
   end subroutine design_command

end module usharp_cmd_design
