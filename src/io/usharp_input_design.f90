!> The &design group: settings of `usharp design` (test-matrix design)
module usharp_input_design
   use usharp_kinds, only: dp
   use usharp_strings, only: real_str
   use usharp_error, only: error_type
   use usharp_namelist, only: nml_file, group_text, find_group, group_error, read_error
   implicit none
   private

   public :: design_config, read_design_group, write_design_defaults

   !> Test-matrix design settings (&design group)
   type :: design_config
      real(dp) :: noise = 0.01_dp     !< sd of the stress data as a fraction of the peak |stress|
      integer :: max_tests = 3        !< largest test matrix (current tests + candidates)
      real(dp) :: ci_target = 0.02_dp !< determined: 95 % interval within this fraction
      real(dp) :: prior_decades = 2.0_dp !< prior sd of log10 c, keeps log det finite
      integer :: top = 10             !< combinations listed
   end type design_config

contains

   !> Read &design (optional) into design
   subroutine read_design_group(file, design, error)
      type(nml_file), intent(in) :: file
      type(design_config), intent(out) :: design
      type(error_type), allocatable, intent(out) :: error
      integer :: ios, k
      character(len=512) :: msg
      character(len=:), allocatable :: lines(:)
      k = find_group(file, 'design')
      if (k == 0) return
      call group_text(file, k, lines)
      call design_namelist(design, ios, msg, text=lines)
      if (ios /= 0) then
         call read_error(error, file, k, 'design', ios, msg, reread)
      else if (.not. (design%noise > 0.0_dp .and. design%noise <= 0.5_dp)) then
         ! (a noise of 1 means 100 % of the peak: 1 % written as a whole number)
         call group_error(error, file%path, 'design', 'noise = '//real_str(design%noise, 'g0.4')// &
            ': it is a fraction of the peak response, in (0, 0.5] (0.01 for 1 %)')
      else if (design%max_tests < 1 .or. design%top < 1) then
         call group_error(error, file%path, 'design', 'max_tests and top must be >= 1')
      else if (.not. (design%ci_target > 0.0_dp .and. design%ci_target <= 1.0_dp)) then
         call group_error(error, file%path, 'design', 'ci_target = '// &
            real_str(design%ci_target, 'g0.4')//': it is a fraction of each constant, in (0, 1] '// &
            '(0.01 for 1 %)')
      else if (.not. (design%prior_decades > 0.0_dp)) then
         call group_error(error, file%path, 'design', 'prior_decades must be > 0')
      end if
   contains
      subroutine reread(lines, ios, msg)
         character(len=*), intent(in) :: lines(:)
         integer, intent(out) :: ios
         character(len=*), intent(out) :: msg
         type(design_config) :: scratch
         call design_namelist(scratch, ios, msg, text=lines)
      end subroutine reread
   end subroutine read_design_group

   !> Write &design with its defaults to unit
   subroutine write_design_defaults(unit)
      integer, intent(in) :: unit
      type(design_config) :: design
      integer :: ios
      character(len=512) :: msg
      call design_namelist(design, ios, msg, unit=unit)
   end subroutine write_design_defaults

   !> The &design namelist, starting from design: read from text or written to unit
   subroutine design_namelist(settings, ios, msg, text, unit)
      type(design_config), intent(inout) :: settings
      integer, intent(out) :: ios
      character(len=*), intent(out) :: msg
      character(len=*), intent(in), optional :: text(:)
      integer, intent(in), optional :: unit
      real(dp) :: noise, ci_target, prior_decades
      integer :: max_tests, top
      namelist /design/ noise, max_tests, ci_target, prior_decades, top
      noise = settings%noise
      max_tests = settings%max_tests
      ci_target = settings%ci_target
      prior_decades = settings%prior_decades
      top = settings%top
      ios = 0
      msg = ''
      if (present(text)) read (text, nml=design, iostat=ios, iomsg=msg)
      if (present(unit)) write (unit, nml=design, iostat=ios, iomsg=msg)
      settings%noise = noise
      settings%max_tests = max_tests
      settings%ci_target = ci_target
      settings%prior_decades = prior_decades
      settings%top = top
   end subroutine design_namelist

end module usharp_input_design
