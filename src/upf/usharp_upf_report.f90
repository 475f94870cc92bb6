!> How the user materials report a material they cannot use. This default serves CalculiX
!> (and any code without a message routine): one line on standard output (unit 6, which
!> CalculiX shows and keeps in its log; its unit 7 is the .frd results file and must not be
!> written). The adapter then asks for a tiny increment, so that the analysis stops at its
!> minimum increment. The single-file Abaqus and ANSYS sources written by
!> scripts/build-umat.sh replace this module by usharp_upf_report_abaqus.inc (message file,
!> then XIT) and usharp_upf_report_ansys.inc (erhandler).
module usharp_upf_report
   implicit none
   private

   public :: upf_report_invalid

   !> Whether a report ends the analysis: here not (the cut-back stops it at its minimum
   !> increment), so the adapters report once per element
   logical, parameter, public :: upf_report_stops = .false.

contains

   !> Report one line: "usharp Miller material NAME: MESSAGE"
   subroutine upf_report_invalid(material, message)
      character(len=*), intent(in) :: material  !< the code's material name or number
      character(len=*), intent(in) :: message   !< what is wrong, naming the constant
      integer :: ios
      ! A failed write cannot be reported anywhere else: the cut-back still stops the run
      write (6, '(a)', iostat=ios) 'usharp Miller material '//trim(material)//': '//trim(message)
      flush (6, iostat=ios)
   end subroutine upf_report_invalid
end module usharp_upf_report
