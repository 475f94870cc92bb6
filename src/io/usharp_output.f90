!> Writing simulated curves
module usharp_output
   use usharp_kinds, only: dp
   use usharp_error, only: error_type, fatal_error, stat_io
   use usharp_simulation, only: sim_result
   implicit none
   private

   public :: write_sim_file, write_lines

contains

   !> Write a simulation result as text: '#' comment lines (header), a '#' line naming the
   !> columns, then rows time, strain, stress, inelastic strain, R, D
   subroutine write_sim_file(path, res, header, units, error)
      character(len=*), intent(in) :: path
      type(sim_result), intent(in) :: res
      character(len=*), intent(in) :: header(:)  !< comment lines, written after '# '
      character(len=*), intent(in) :: units      !< stress unit
      type(error_type), allocatable, intent(out) :: error
      integer :: unit, ios, i
      character(len=256) :: msg
      open (newunit=unit, file=path, status='replace', action='write', iostat=ios, iomsg=msg)
      if (ios /= 0) then
         call fatal_error(error, path//': cannot write ('//trim(msg)//')', stat_io)
         return
      end if
      do i = 1, size(header)
         write (unit, '(a)') '# '//trim(header(i))
      end do
      write (unit, '(a)') '# columns: time (s), strain (-), stress ('//units// &
         '), inelastic strain (-), back stress R ('//units//'), drag stress D ('//units//')'
      write (unit, '(a)') '# time strain stress eps_in back_stress drag_stress'
      do i = 1, size(res%t)
         write (unit, '(6es24.15e3)', iostat=ios) res%t(i), res%strain(i), res%stress(i), &
            res%eps_in(i), res%back(i), res%drag(i)
         if (ios /= 0) exit
      end do
      close (unit)
      if (ios /= 0) call fatal_error(error, path//': write failed', stat_io)
   end subroutine write_sim_file

   !> Write lines of text (trailing blanks trimmed) to a file, replacing it
   subroutine write_lines(file, lines, error)
      character(len=*), intent(in) :: file
      character(len=*), intent(in) :: lines(:)
      type(error_type), allocatable, intent(out) :: error
      integer :: unit, ios, k
      open (newunit=unit, file=file, status='replace', action='write', iostat=ios)
      if (ios /= 0) then
         call fatal_error(error, file//': cannot write', stat_io)
         return
      end if
      do k = 1, size(lines)
         write (unit, '(a)') trim(lines(k))
      end do
      close (unit)
   end subroutine write_lines
end module usharp_output
