!> Writing result files whole or not at all. A result file is gathered in memory, written
!> under a temporary name in its own folder (<name>.part) through the C library (every
!> write, the sync and the close checked), and only a complete file is renamed into place (rename is atomic within a file system): a reader
!> never sees half a file, and a failed write (a full disk) leaves the old file untouched and
!> is an error (exit 4) that names the file. Every command writes its results through here.
module usharp_output
   use usharp_kinds, only: dp
   use usharp_error, only: error_type, fatal_error, stat_io
   use usharp_simulation, only: sim_result
   use usharp_filesys, only: rename_file, remove_file, raw_file
   implicit none
   private

   public :: result_file, write_sim_file, write_lines

   !> A result file being written: its text is gathered in memory and written at commit
   type :: result_file
      character(len=:), allocatable :: path  !< the final name
      character(len=:), allocatable :: text  !< the contents so far (text(:used))
      integer :: used = 0
   contains
      procedure :: open => result_open
      procedure :: line => result_line
      procedure :: commit => result_commit
   end type result_file

contains

   !> Start a result file path (nothing is written before commit)
   subroutine result_open(self, path, error)
      class(result_file), intent(inout) :: self
      character(len=*), intent(in) :: path
      type(error_type), allocatable, intent(out) :: error
      self%path = path
      self%used = 0
      if (allocated(self%text)) deallocate (self%text)
      allocate (character(len=4096) :: self%text)
   end subroutine result_open

   !> Add one line (trailing blanks trimmed)
   subroutine result_line(self, text)
      class(result_file), intent(inout) :: self
      character(len=*), intent(in) :: text
      character(len=:), allocatable :: grown
      integer :: n
      n = len_trim(text) + 1
      if (self%used + n > len(self%text)) then
         allocate (character(len=max(2*len(self%text), self%used + n)) :: grown)
         grown(:self%used) = self%text(:self%used)
         call move_alloc(grown, self%text)
      end if
      self%text(self%used + 1:self%used + n) = trim(text)//new_line('a')
      self%used = self%used + n
   end subroutine result_line

   !> Write the file under <path>.part in the same folder (every write, the sync and the
   !> close checked), then rename it into place. On a failure the partial file is removed,
   !> an old file of that name is left as it was, and the error names the file (exit 4).
   !> sync (default true): wait until the contents are on the disk before the rename; a
   !> scratch file that a crash may lose (an external command's input) skips the wait.
   subroutine result_commit(self, error, sync)
      class(result_file), intent(inout) :: self
      type(error_type), allocatable, intent(out) :: error
      logical, intent(in), optional :: sync
      type(raw_file) :: f
      logical :: durable
      character(len=:), allocatable :: temp
      logical :: gone
      durable = .true.
      if (present(sync)) durable = sync
      temp = self%path//'.part'
      call f%create(temp, error)
      if (.not. allocated(error)) call f%put(self%text(:self%used), error)
      if (.not. allocated(error) .and. durable) call f%sync(error)
      if (allocated(error)) then
         call f%close()
      else
         call f%close(error)
      end if
      if (.not. allocated(error)) call rename_file(temp, self%path, error)
      if (allocated(error)) then
         gone = remove_file(temp)
         ! Name the result file, not its temporary name
         error%message = self%path//': '//after_colon(error%message)
      end if
   contains
      pure function after_colon(message) result(rest)
         character(len=*), intent(in) :: message
         character(len=:), allocatable :: rest
         integer :: k
         k = index(message, ': ')
         rest = message(k + 2:)
      end function after_colon
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

   !> Write lines of text (trailing blanks trimmed) to a file, replacing it whole; sync: see
   !> result_commit
   subroutine write_lines(file, lines, error, sync)
      character(len=*), intent(in) :: file
      character(len=*), intent(in) :: lines(:)
      type(error_type), allocatable, intent(out) :: error
      logical, intent(in), optional :: sync
      type(result_file) :: out
      integer :: k
      call out%open(file, error)
      if (allocated(error)) return
      do k = 1, size(lines)
         call out%line(lines(k))
      end do
      call out%commit(error, sync)
   end subroutine write_lines
end module usharp_output
