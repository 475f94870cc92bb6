!> Writing result files whole or not at all. A result file is written under a temporary
!> name in its own folder (<name>.part), every write and the close are checked, and only a
!> complete file is renamed into place (rename is atomic within a file system): a reader
!> never sees half a file, and a failed write (a full disk) leaves the old file untouched and
!> is an error (exit 4) that names the file. Every command writes its results through here.
module usharp_output
   use usharp_kinds, only: dp
   use usharp_error, only: error_type, fatal_error, stat_io
   use usharp_simulation, only: sim_result
   use usharp_filesys, only: rename_file, remove_file
   implicit none
   private

   public :: result_file, write_sim_file, write_lines

   !> A result file being written
   type :: result_file
      character(len=:), allocatable :: path  !< the final name
      character(len=:), allocatable :: temp  !< the name while it is written
      integer :: unit = 0
      logical :: opened = .false.
      integer :: ios = 0                     !< first failure of a write (0: none)
      character(len=256) :: msg = ''
   contains
      procedure :: open => result_open
      procedure :: line => result_line
      procedure :: commit => result_commit
   end type result_file

contains

   !> Start writing the result file path (under its temporary name)
   subroutine result_open(self, path, error)
      class(result_file), intent(inout) :: self
      character(len=*), intent(in) :: path
      type(error_type), allocatable, intent(out) :: error
      self%path = path
      self%temp = path//'.part'
      self%ios = 0
      self%msg = ''
      open (newunit=self%unit, file=self%temp, status='replace', action='write', &
            iostat=self%ios, iomsg=self%msg)
      self%opened = self%ios == 0
      if (.not. self%opened) then
         call fatal_error(error, path//': cannot write ('//trim(self%msg)//')', stat_io)
      end if
   end subroutine result_open

   !> Write one line (trailing blanks trimmed); a failure is kept and reported by commit
   subroutine result_line(self, text)
      class(result_file), intent(inout) :: self
      character(len=*), intent(in) :: text
      if (self%ios /= 0 .or. .not. self%opened) return
      write (self%unit, '(a)', iostat=self%ios, iomsg=self%msg) trim(text)
   end subroutine result_line

   !> Finish the file: flush and close (checked), then rename it into place. On any failure
   !> the temporary file is removed and the error names the file.
   subroutine result_commit(self, error)
      class(result_file), intent(inout) :: self
      type(error_type), allocatable, intent(out) :: error
      integer :: ios
      character(len=256) :: msg
      logical :: gone
      if (.not. self%opened) then
         call fatal_error(error, self%path//': cannot write', stat_io)
         return
      end if
      if (self%ios == 0) flush (self%unit, iostat=self%ios, iomsg=self%msg)
      ios = 0
      close (self%unit, iostat=ios, iomsg=msg)
      self%opened = .false.
      if (self%ios == 0 .and. ios /= 0) then
         self%ios = ios
         self%msg = msg
      end if
      if (self%ios /= 0) then
         gone = remove_file(self%temp)
         call fatal_error(error, self%path//': write failed ('//trim(self%msg)//')', stat_io)
         return
      end if
      call rename_file(self%temp, self%path, error)
      if (allocated(error)) gone = remove_file(self%temp)
   end subroutine result_commit

   !> Write a simulation result as text: '#' comment lines (header), a '#' line naming the
   !> columns, then rows time, strain, stress, inelastic strain, R, D
   subroutine write_sim_file(path, res, header, units, error)
      character(len=*), intent(in) :: path
      type(sim_result), intent(in) :: res
      character(len=*), intent(in) :: header(:)  !< comment lines, written after '# '
      character(len=*), intent(in) :: units      !< stress unit
      type(error_type), allocatable, intent(out) :: error
      type(result_file) :: out
      character(len=160) :: row
      integer :: i
      call out%open(path, error)
      if (allocated(error)) return
      do i = 1, size(header)
         call out%line('# '//trim(header(i)))
      end do
      call out%line('# columns: time (s), strain (-), stress ('//units// &
         '), inelastic strain (-), back stress R ('//units//'), drag stress D ('//units//')')
      call out%line('# time strain stress eps_in back_stress drag_stress')
      do i = 1, size(res%t)
         write (row, '(6es24.15e3)') res%t(i), res%strain(i), res%stress(i), &
            res%eps_in(i), res%back(i), res%drag(i)
         call out%line(row)
      end do
      call out%commit(error)
   end subroutine write_sim_file

   !> Write lines of text (trailing blanks trimmed) to a file, replacing it whole
   subroutine write_lines(file, lines, error)
      character(len=*), intent(in) :: file
      character(len=*), intent(in) :: lines(:)
      type(error_type), allocatable, intent(out) :: error
      type(result_file) :: out
      integer :: k
      call out%open(file, error)
      if (allocated(error)) return
      do k = 1, size(lines)
         call out%line(lines(k))
      end do
      call out%commit(error)
   end subroutine write_lines
end module usharp_output
