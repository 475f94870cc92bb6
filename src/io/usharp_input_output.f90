!> The &output group: where results are written
module usharp_input_output
   use usharp_error, only: error_type
   use usharp_namelist, only: nml_file, group_text, find_group, group_error, read_error, check_length, &
                              value_len, resolve_path
   implicit none
   private

   public :: output_config, read_output_group, write_output_defaults

   !> Output settings (&output group)
   type :: output_config
      !> Output folder, relative to the input file's folder
      character(len=value_len) :: out_dir = 'out'
   end type output_config

contains

   !> Read &output (optional); out_dir comes back resolved against the input file's folder
   subroutine read_output_group(file, out_dir, error)
      type(nml_file), intent(in) :: file
      character(len=:), allocatable, intent(out) :: out_dir
      type(error_type), allocatable, intent(out) :: error
      type(output_config) :: settings
      integer :: ios, k
      character(len=512) :: msg
      character(len=:), allocatable :: lines(:)
      k = find_group(file, 'output')
      if (k > 0) then
         call group_text(file, k, lines)
         call output_namelist(settings, ios, msg, text=lines)
         if (ios /= 0) then
            call read_error(error, file, k, 'output', ios, msg, reread)
            return
         end if
      end if
      call check_length(error, file%path//': &output: ', 'out_dir', settings%out_dir)
      if (allocated(error)) return
      if (len_trim(settings%out_dir) == 0) then
         call group_error(error, file%path, 'output', 'out_dir is empty')
         return
      end if
      out_dir = resolve_path(file%base_dir, trim(settings%out_dir))
   contains
      subroutine reread(lines, ios, msg)
         character(len=*), intent(in) :: lines(:)
         integer, intent(out) :: ios
         character(len=*), intent(out) :: msg
         type(output_config) :: scratch
         call output_namelist(scratch, ios, msg, text=lines)
      end subroutine reread
   end subroutine read_output_group

   !> Write &output with its defaults to unit
   subroutine write_output_defaults(unit)
      integer, intent(in) :: unit
      type(output_config) :: settings
      integer :: ios
      character(len=512) :: msg
      call output_namelist(settings, ios, msg, unit=unit)
   end subroutine write_output_defaults

   !> The &output namelist, starting from settings: read from text or written to unit
   subroutine output_namelist(settings, ios, msg, text, unit)
      type(output_config), intent(inout) :: settings
      integer, intent(out) :: ios
      character(len=*), intent(out) :: msg
      character(len=*), intent(in), optional :: text(:)
      integer, intent(in), optional :: unit
      character(len=value_len) :: out_dir
      namelist /output/ out_dir
      out_dir = settings%out_dir
      ios = 0
      msg = ''
      if (present(text)) read (text, nml=output, iostat=ios, iomsg=msg)
      if (present(unit)) write (unit, nml=output, iostat=ios, iomsg=msg)
      settings%out_dir = out_dir
   end subroutine output_namelist

end module usharp_input_output
