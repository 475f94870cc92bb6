!> `usharp identify`: the identifiability report of the &fit constants at the input's
!> constants (or those of a best.nml), written to <out_dir>/identify.txt
module usharp_cmd_identify
   use usharp_kinds, only: dp
   use usharp_error, only: error_type
   use usharp_config, only: run_config
   use usharp_input, only: read_config_as, check_inputs_kept, check_not_a_fit
   use usharp_objective, only: fit_problem, setup_problem
   use usharp_identify, only: identify_result, identify_at, identify_report
   use usharp_filesys, only: make_dir, join_path
   use usharp_output, only: write_lines
   use usharp_strings, only: report_line_len
   use usharp_overwrite, only: check_overwrite
   implicit none
   private

   public :: identify_command

contains

   !> The report at the constants of path (or of constants_file, a best.nml, when not ''),
   !> written to identify.txt in out_dir (&output out_dir when ''), and returned in lines. An
   !> identify.txt there that an earlier report did not write is refused unless force (--force).
   subroutine identify_command(path, out_dir, constants_file, lines, error, force)
      character(len=*), intent(in) :: path, out_dir, constants_file
      character(len=report_line_len), allocatable, intent(out) :: lines(:)
      type(error_type), allocatable, intent(out) :: error
      !> write over an identify.txt that usharp identify did not write
      logical, intent(in), optional :: force
      type(run_config) :: cfg
      type(fit_problem) :: prob
      type(identify_result) :: res
      real(dp), allocatable :: c(:)
      integer :: j
      logical :: overwrite
      overwrite = .false.
      if (present(force)) overwrite = force
      call read_config_as(path, constants_file, out_dir, cfg, error)
      if (allocated(error)) return
      call check_inputs_kept(cfg, path, constants_file, ['identify.txt'], [character(len=1) ::], error)
      if (.not. allocated(error)) call check_not_a_fit(cfg, 'identify', ['identify.txt'], &
                                                       [character(len=1) ::], error)
      if (allocated(error)) return
      call check_overwrite(cfg%out_dir, ['identify.txt'], [character(len=36) :: &
                           'identifiability at the optimum (', 'identifiability at these constants ('], &
                           'identify', overwrite, error)
      if (allocated(error)) return
      call setup_problem(cfg, prob, error)
      if (allocated(error)) return
      c = [(cfg%model%get_constant(prob%idx(j)), j=1, size(prob%idx))]
      call identify_at(prob, c, cfg%fit%fd_step, res, error)
      if (allocated(error)) return
      lines = identify_report(res)
      call make_dir(cfg%out_dir, error)
      if (allocated(error)) return
      call write_lines(join_path(cfg%out_dir, 'identify.txt'), lines, error)
   end subroutine identify_command

end module usharp_cmd_identify
