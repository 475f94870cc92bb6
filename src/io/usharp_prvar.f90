!> Reader for the listing that ANSYS POST26 PRVAR writes: page headers of any length, the
!> column-title block repeated after every page break, then rows of numbers. Columns are found
!> by their titles, so the variables may be listed in any order.
!>
!> A title block is every non-numeric line since the last data row. In each of its lines the
!> variable reference numbers (bare integers) are dropped; a line whose remaining words count
!> as many as the data columns names them in order, one with a word fewer names the columns
!> after TIME (as PRVAR's second title line does). A title may also be a column position.
module usharp_prvar
   use usharp_kinds, only: dp
   use usharp_error, only: error_type, fatal_error
   use usharp_strings, only: lower, str, join
   implicit none
   private

   public :: read_prvar, is_number

   integer, parameter :: line_len = 4096, max_words = 64, word_len = 64

contains

   !> Read the columns titled titles(:) (case-insensitive, or 1-based positions) of a PRVAR
   !> listing into values(npoint, size(titles)). Errors name the file and the line.
   subroutine read_prvar(file, titles, values, error)
      character(len=*), intent(in) :: file
      character(len=*), intent(in) :: titles(:)
      real(dp), allocatable, intent(out) :: values(:, :)
      type(error_type), allocatable, intent(out) :: error
      character(len=line_len) :: line
      character(len=word_len) :: words(max_words)
      character(len=line_len), allocatable :: block(:)
      character(len=256) :: msg
      real(dp), allocatable :: buf(:, :)
      real(dp) :: row(max_words)
      integer :: unit, ios, lineno, nword, ncol, npt, icol(size(titles)), j
      logical :: numeric, prev_data

      open (newunit=unit, file=file, status='old', action='read', iostat=ios, iomsg=msg)
      if (ios /= 0) then
         call fatal_error(error, file//': cannot open ('//trim(msg)//')')
         return
      end if
      allocate (block(0), buf(size(titles), 1024))
      lineno = 0
      ncol = 0
      prev_data = .false.
      npt = 0
      do
         read (unit, '(a)', iostat=ios) line
         if (ios /= 0) exit
         lineno = lineno + 1
         call split_words(line, words, nword)
         if (nword == 0) cycle
         numeric = is_number(words(1))
         if (numeric) then
            do j = 2, nword
               if (.not. is_number(words(j))) then
                  call fatal_error(error, file//':'//str(lineno)//": garbled row: '"// &
                     trim(words(j))//"' is not a number")
                  exit
               end if
            end do
            if (allocated(error)) exit
         end if
         if (.not. numeric) then
            ! A title or page-header line: the first after data rows starts a new block
            if (prev_data) then
               deallocate (block)
               allocate (block(0))
            end if
            block = [character(len=line_len) :: block, line]
            prev_data = .false.
            cycle
         end if
         ! A data row; the first after a title block finds the columns again
         if (.not. prev_data) then
            call find_columns(block, nword, titles, icol, error)
            if (allocated(error)) then
               error%message = file//':'//str(lineno)//': '//error%message
               exit
            end if
            ncol = nword
         end if
         prev_data = .true.
         if (nword /= ncol) then
            call fatal_error(error, file//':'//str(lineno)//': garbled row: '//str(nword)// &
               ' numbers where the titles name '//str(ncol)//' columns')
            exit
         end if
         do j = 1, nword
            read (words(j), *) row(j)
         end do
         npt = npt + 1
         if (npt > size(buf, 2)) buf = reshape(buf, [size(buf, 1), 2*size(buf, 2)], pad=[0.0_dp])
         buf(:, npt) = row(icol)
      end do
      close (unit)
      if (allocated(error)) return
      if (npt == 0) then
         call fatal_error(error, file//': no data rows (an empty or truncated listing)')
         return
      end if
      values = transpose(buf(:, :npt))

   end subroutine read_prvar

   !> Columns of the wanted titles in the title block, for rows of ncol numbers
   pure subroutine find_columns(block, ncol, titles, icol, error)
      character(len=*), intent(in) :: block(:)
      integer, intent(in) :: ncol
      character(len=*), intent(in) :: titles(:)
      integer, intent(out) :: icol(:)
      type(error_type), allocatable, intent(out) :: error
      character(len=word_len) :: words(max_words), names(max_words)
      character(len=:), allocatable :: seen
      integer :: i, j, k, nword, nname, pos, ios
      icol = 0
      seen = ''
      do i = 1, size(titles)
         read (titles(i), *, iostat=ios) pos
         if (ios == 0 .and. verify(trim(titles(i)), '0123456789') == 0) then
            if (pos < 1 .or. pos > ncol) then
               call fatal_error(error, 'column '//trim(titles(i))//' does not exist (rows have '// &
                  str(ncol)//' columns)')
               return
            end if
            icol(i) = pos
         end if
      end do
      do k = 1, size(block)
         call split_words(block(k), words, nword)
         nname = 0
         do j = 1, nword
            if (verify(trim(words(j)), '0123456789') == 0) cycle  ! a variable reference number
            nname = nname + 1
            names(nname) = words(j)
         end do
         if (nname == ncol - 1) then
            names(2:ncol) = names(1:ncol - 1)
            names(1) = 'TIME'
         else if (nname /= ncol) then
            cycle
         end if
         seen = seen//' '//join(names(:ncol), ' ')
         do i = 1, size(titles)
            if (icol(i) > 0) cycle
            do j = 1, ncol
               if (lower(trim(names(j))) == lower(trim(titles(i)))) then
                  icol(i) = j
                  exit
               end if
            end do
         end do
      end do
      do i = 1, size(titles)
         if (icol(i) == 0) then
            if (len(seen) == 0) then
               call fatal_error(error, 'no title line names the '//str(ncol)//' columns of the rows')
            else
               call fatal_error(error, "no column titled '"//trim(titles(i))//"' (titles:"// &
                  seen//')')
            end if
            return
         end if
      end do
   end subroutine find_columns

   !> Words of a line separated by blanks, tabs or form feeds
   pure subroutine split_words(line, words, nword)
      character(len=*), intent(in) :: line
      character(len=*), intent(out) :: words(:)
      integer, intent(out) :: nword
      integer :: i, start
      logical :: inword
      nword = 0
      inword = .false.
      start = 1
      do i = 1, len_trim(line) + 1
         if (i <= len_trim(line)) then
            if (.not. is_blank(line(i:i))) then
               if (.not. inword) start = i
               inword = .true.
               cycle
            end if
         end if
         if (inword .and. nword < size(words)) then
            nword = nword + 1
            words(nword) = line(start:i - 1)
         end if
         inword = .false.
      end do
   contains
      pure logical function is_blank(c)
         character, intent(in) :: c
         is_blank = c == ' ' .or. c == achar(9) .or. c == achar(12) .or. c == achar(13)
      end function is_blank
   end subroutine split_words

   !> Whether a word is a plain Fortran real or integer literal (digits, sign, point, exponent)
   pure logical function is_number(word)
      character(len=*), intent(in) :: word
      real(dp) :: x
      integer :: ios
      is_number = .false.
      if (len_trim(word) == 0) return
      if (verify(trim(word), '0123456789+-.EeDd') /= 0) return
      if (scan(trim(word), '0123456789') == 0) return
      read (word, *, iostat=ios) x
      is_number = ios == 0
   end function is_number
end module usharp_prvar
