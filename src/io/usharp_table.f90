!> Reader for measured data tables: comma or white-space separated, '#' comments, an optional
!> header row, quoted fields; columns picked by name or position; an optional row filter on a
!> column's text; and the original's fixed-format files through a Fortran format string.
module usharp_table
   use, intrinsic :: ieee_arithmetic, only: ieee_is_nan, ieee_is_finite
   use usharp_kinds, only: dp
   use usharp_error, only: error_type, fatal_error
   use usharp_strings, only: lower, str, split_fields
   use usharp_filesys, only: read_whole_file, check_text
   implicit none
   private

   public :: read_columns, merge_repeated_times, numbers_format

   integer, parameter :: max_fields = 64, field_len = 128, line_len = 4096

contains

   !> Read the named columns of a data file into values(npoint, size(columns)).
   !> A column is given by its header name (case-insensitive, surrounding blanks ignored) or by
   !> its 1-based position. With filter_column, only rows whose text in that column equals one
   !> of filter_values are kept. With fmt (a Fortran format such as '(2E12.5)'), each data line
   !> is read with that format and columns must be positions.
   subroutine read_columns(file, columns, values, error, filter_column, filter_values, fmt, &
                           skip_missing, unnamed, time_first)
      character(len=*), intent(in) :: file
      character(len=*), intent(in) :: columns(:)
      real(dp), allocatable, intent(out) :: values(:, :)
      type(error_type), allocatable, intent(out) :: error
      character(len=*), intent(in), optional :: filter_column
      character(len=*), intent(in), optional :: filter_values(:)
      character(len=*), intent(in), optional :: fmt
      !> drop the rows where a requested field is empty or '.' (a missing value)
      logical, intent(in), optional :: skip_missing
      !> the columns' positions in a file that names none (no header row): a file of bare
      !> numbers is read by these, one with a header by the names in columns
      character(len=*), intent(in), optional :: unnamed(:)
      !> the first column is time: a row whose time is below the row's before is an error at
      !> its line and column (rows of equal time are merged later: merge_repeated_times)
      logical, intent(in), optional :: time_first

      character(len=:), allocatable :: text
      character(len=field_len) :: fields(max_fields), header(max_fields), last_label
      character(len=line_len) :: last_comment
      integer :: ios, nfield, nheader, lineno, npt, j, icol(size(columns)), ifilter, first
      integer :: a, b, next
      !> Field counts every row must have, from the header (or the first data row): at least
      !> nlong less its empty last fields, at most nlong; nshort is nlong without them
      integer :: nlong, nshort, nfull
      character(len=:), allocatable :: counted_from
      logical :: have_header, filtering, fixed
      !> the columns were found by the positions unnamed (a file without a header row)
      logical :: by_position
      !> Of the filter values, those some row holds; the first values the filter column holds,
      !> each after ', '
      logical, allocatable :: matched(:), hit(:)
      character(len=:), allocatable :: seen
      integer :: nseen
      logical :: more_seen   !< labels beyond the nseen listed
      real(dp), allocatable :: buf(:, :)
      real(dp) :: row(max_fields)

      by_position = .false.
      filtering = .false.
      if (present(filter_column)) filtering = len_trim(filter_column) > 0
      if (filtering) then
         allocate (matched(size(filter_values)), hit(size(filter_values)))
         matched = .false.
         seen = ''
         nseen = 0
         more_seen = .false.
         last_label = achar(0)
      end if
      fixed = .false.
      if (present(fmt)) fixed = len_trim(fmt) > 0
      ! The file in one read, then its lines as slices of it: a formatted read per line took
      ! most of the time of reading a long file
      call read_whole_file(file, text, error)
      if (.not. allocated(error)) call check_text(file, text, error)
      if (allocated(error)) return
      have_header = .false.
      nheader = 0
      icol = 0
      ifilter = 0
      nlong = -1
      nshort = -1
      npt = 0
      lineno = 0
      last_comment = ''
      allocate (buf(size(columns), 1024))
      next = 1
      do while (next <= len(text))
         ! The line is text(a:b), without its end (LF, or CR LF)
         a = next
         b = line_end(text, a)
         next = b + 2
         if (b >= a) then
            if (text(b:b) == achar(13)) b = b - 1
         end if
         lineno = lineno + 1
         ! A spreadsheet's 'CSV UTF-8' starts with a byte order mark, not part of the first name
         if (lineno == 1 .and. b - a + 1 >= 3) then
            if (text(a:a + 2) == achar(239)//achar(187)//achar(191)) a = a + 3
         end if
         b = a - 1 + len_trim(text(a:b))
         if (b < a) cycle
         first = a - 1 + verify(text(a:b), ' ')
         if (text(first:first) == '#') then
            last_comment = text(first + 1:b)
            cycle
         end if
         if (fixed) then
            call read_fixed(text(a:b), fmt, row, nfield, ios)
            if (ios /= 0) then
               call fatal_error(error, file//':'//str(lineno)//': does not match format '//trim(fmt))
               exit
            end if
            if (npt == 0) call resolve_positions(nfield, columns)
            if (allocated(error)) exit
            call append([(row(icol(j)), j=1, size(columns))])
            cycle
         end if
         call split_fields(text(a:b), fields, nfield)
         if (nfield > max_fields) then
            call fatal_error(error, file//':'//str(lineno)//': more than '//str(max_fields)//' columns')
            exit
         end if
         if (.not. have_header .and. npt == 0 .and. nheader == 0) then
            if (.not. all_numeric(fields(:nfield))) then
               ! The first non-comment row with text is the header
               have_header = .true.
               nheader = nfield
               header(:nfield) = fields(:nfield)
               call set_counts('the header names')
               call resolve_names()
               if (allocated(error)) exit
               cycle
            end if
            ! No header row: a comment line just above the data that names as many columns
            ! as the data have serves as the header ('# time strain stress')
            call split_fields(last_comment, header, nheader)
            if (nheader == nfield .and. .not. all_numeric(header(:nheader)) .and. &
                .not. all_positions()) then
               call resolve_names()
               call set_counts('the header names')
            else if (present(unnamed)) then
               by_position = .true.
               call resolve_positions(nfield, unnamed)
               call set_counts('the first row')
            else
               call resolve_positions(nfield, columns)
               call set_counts('the first row')
            end if
            if (allocated(error)) exit
            nheader = -1
         end if
         ! A row of more or fewer fields than the header names would be read with its values
         ! under the wrong names (decimal commas split each number in two); empty last fields
         ! (a spreadsheet's trailing commas) do not count
         nfull = nfield - count_empty_tail()
         if (nfull > nlong .or. nfield < nshort) then
            call fatal_error(error, file//':'//str(lineno)//': row has '//str(nfull)// &
               ' fields, '//counted_from//' '//str(nshort)//hint())
            exit
         end if
         if (filtering) then
            if (ifilter > nfield) cycle
            ! (rows come in runs of one label: a label is looked up only where it changes)
            if (.not. more_seen .and. fields(ifilter) /= last_label) then
               if (index(seen//', ', ', '//trim(fields(ifilter))//', ') == 0) then
                  if (nseen < 12) then
                     seen = seen//', '//trim(fields(ifilter))
                     nseen = nseen + 1
                  else
                     more_seen = .true.
                  end if
               end if
            end if
            last_label = fields(ifilter)
            hit = fields(ifilter) == filter_values
            if (.not. any(hit)) cycle
            matched = matched .or. hit
         end if
         if (present(skip_missing)) then
            if (skip_missing .and. any([(missing(fields(min(icol(j), nfield))), j=1, size(columns))])) cycle
         end if
         do j = 1, size(columns)
            if (icol(j) > nfield) then
               call fatal_error(error, file//':'//str(lineno)//': row has '//str(nfield)// &
                  ' columns, column '//label(j)//' is missing')
               exit
            end if
            call to_real(fields(icol(j)), row(j), ios)
            if (ios /= 0) then
               call fatal_error(error, file//':'//str(lineno)//':'//str(icol(j))//": '"// &
                  trim(fields(icol(j)))//"' in column "//label(j)//' is not a number')
               exit
            end if
            if (.not. ieee_is_finite(row(j))) then
               call fatal_error(error, file//':'//str(lineno)//':'//str(icol(j))//': '// &
                  trim(fields(icol(j)))//' in column '//label(j)//' is not finite')
               exit
            end if
         end do
         if (allocated(error)) exit
         if (present(time_first) .and. npt > 0) then
            if (time_first .and. row(1) < buf(1, npt)) then
               call fatal_error(error, file//':'//str(lineno)//':'//str(icol(1))//': time is '// &
                  'not increasing ('//str(row(1))//' s after '//str(buf(1, npt))//' s)')
               exit
            end if
         end if
         call append(row(:size(columns)))
      end do
      if (allocated(error)) return
      if (filtering .and. .not. fixed) then
         ! A filter value no row holds is a typing error, not a request for fewer rows
         do j = 1, size(filter_values)
            if (matched(j)) cycle
            call fatal_error(error, file//": filter: no row has '"//trim(filter_values(j))// &
               "' in column "//trim(filter_column)//' (it holds: '// &
               seen(3:)//trim(merge(', ...', '     ', more_seen))//')')
            return
         end do
      end if
      if (npt < 3) then
         call fatal_error(error, file//': needs at least 3 data rows, found '//str(npt))
         return
      end if
      values = transpose(buf(:, :npt))

   contains

      !> The field counts rows are held to, from the fields just split (the header row, or
      !> the first data row of a file without one)
      subroutine set_counts(what)
         !> what the counts come from, for the message
         character(len=*), intent(in) :: what
         counted_from = what
         nlong = nfield
         nshort = nfield - count_empty_tail()
      end subroutine set_counts

      !> The likely cause of a row longer than the header in a comma separated file
      function hint() result(advice)
         character(len=:), allocatable :: advice
         advice = ''
         ! (a comma splits the row: in a file separated by blanks one decimal comma makes the
         ! row comma-separated, and its fields fewer)
         if (index(text(a:b), ',') > 0) &
            advice = ' (decimal commas? a field holding a comma needs double quotes)'
      end function hint

      !> How many of the last fields just split are empty
      integer function count_empty_tail() result(n)
         n = 0
         do while (n < nfield)
            if (len_trim(fields(nfield - n)) > 0) exit
            n = n + 1
         end do
      end function count_empty_tail

      pure logical function missing(field)
         character(len=*), intent(in) :: field
         missing = len_trim(field) == 0 .or. trim(adjustl(field)) == '.'
      end function missing

      subroutine append(vals)
         real(dp), intent(in) :: vals(:)
         real(dp), allocatable :: tmp(:, :)
         if (npt == size(buf, 2)) then
            allocate (tmp(size(buf, 1), 2*size(buf, 2)))
            tmp(:, :npt) = buf(:, :npt)
            call move_alloc(tmp, buf)
         end if
         npt = npt + 1
         buf(:, npt) = vals
      end subroutine append

      !> Column j as the messages name it: as asked, or by its position in a file that names none
      function label(j) result(text)
         integer, intent(in) :: j
         character(len=:), allocatable :: text
         if (by_position) then
            text = trim(unnamed(j))
         else
            text = trim(columns(j))
         end if
      end function label

      subroutine resolve_names()
         integer :: k, m
         do k = 1, size(columns)
            icol(k) = 0
            do m = 1, nheader
               if (lower(trim(adjustl(header(m)))) == lower(trim(adjustl(columns(k))))) then
                  icol(k) = m
                  exit
               end if
            end do
            if (icol(k) == 0) icol(k) = position(columns(k), nheader)
            if (icol(k) == 0) then
               ! One header cell holding the others behind semicolons: a file of a locale
               ! whose decimal mark is the comma
               if (nheader == 1 .and. index(header(1), ';') > 0) then
                  call fatal_error(error, file//": no column '"//trim(columns(k))// &
                     "' (the header is one column, '"//trim(adjustl(header(1)))//"': the columns "// &
                     'are separated by semicolons; usharp reads commas, spaces or tabs, and a '// &
                     'point as the decimal mark)')
               else if (count_numeric(header(:nheader)) > nheader/2) then
                  ! Mostly numbers: a file without a header whose first row has a field that
                  ! is not one, read as the header for it
                  m = first_text(header(:nheader))
                  call fatal_error(error, file//':'//str(lineno)//": no column '"//trim(columns(k))// &
                     "': this first row of values is read as a header, as '"//trim(adjustl(header(m)))// &
                     "' in its column "//str(m)//' is not a number (a file without a header: fix that '// &
                     'value; else give the header row)')
               else
                  call fatal_error(error, file//": no column '"//trim(columns(k))// &
                     "' (columns: "//joined(header(:nheader))//')')
               end if
               return
            end if
         end do
         if (filtering) then
            ifilter = 0
            do m = 1, nheader
               if (lower(trim(adjustl(header(m)))) == lower(trim(adjustl(filter_column)))) ifilter = m
            end do
            if (ifilter == 0) ifilter = position(filter_column, nheader)
            if (ifilter == 0) call fatal_error(error, file//": no filter column '"// &
               trim(filter_column)//"' (columns: "//joined(header(:nheader))//')')
         end if
      end subroutine resolve_names

      logical function all_positions()
         integer :: k
         all_positions = .true.
         do k = 1, size(columns)
            if (verify(trim(adjustl(columns(k))), '0123456789') /= 0) all_positions = .false.
         end do
      end function all_positions

      subroutine resolve_positions(ncol, cols)
         integer, intent(in) :: ncol
         character(len=*), intent(in) :: cols(:)
         integer :: k
         do k = 1, size(cols)
            icol(k) = position(cols(k), ncol)
            if (icol(k) == 0) then
               call fatal_error(error, file//": column '"//trim(cols(k))// &
                  "' not found: the file has no header row and "//str(ncol)//' columns')
               return
            end if
         end do
         if (filtering) then
            ifilter = position(filter_column, ncol)
            if (ifilter == 0) call fatal_error(error, file//": filter column '"// &
               trim(filter_column)//"' not found")
         end if
      end subroutine resolve_positions
   end subroutine read_columns

   !> The last character of the line that starts at a in text (before its line feed; a - 1
   !> for an empty line): a loop, where the intrinsic index took a tenth of reading a file
   pure integer function line_end(text, a) result(b)
      character(len=*), intent(in) :: text
      integer, intent(in) :: a
      do b = a, len(text)
         if (text(b:b) == new_line('a')) exit
      end do
      b = b - 1
   end function line_end

   !> Position given as a number 1..ncol, else 0
   integer function position(text, ncol) result(pos)
      character(len=*), intent(in) :: text
      integer, intent(in) :: ncol
      integer :: ios
      read (text, *, iostat=ios) pos
      if (ios /= 0 .or. verify(trim(adjustl(text)), '0123456789') /= 0) pos = 0
      if (pos < 1 .or. pos > ncol) pos = 0
   end function position

   !> Whether fmt is a Fortran format that reads numbers (such as '(2E12.5)'): a blank record
   !> read with it gives zeros, where a format that is none, or one of text, fails
   logical function numbers_format(fmt) result(ok)
      character(len=*), intent(in) :: fmt
      real(dp) :: row(max_fields)
      character(len=line_len) :: blank
      integer :: ios
      blank = ''
      read (blank, fmt, iostat=ios) row
      ok = ios <= 0
   end function numbers_format

   subroutine read_fixed(line, fmt, row, nfield, ios)
      character(len=*), intent(in) :: line, fmt
      real(dp), intent(out) :: row(:)
      integer, intent(out) :: nfield, ios
      integer :: k
      row = ieee_nan()
      read (line, fmt, iostat=ios) row
      if (ios < 0) ios = 0  ! a short record leaves the rest unset
      nfield = 0
      do k = 1, size(row)
         if (ieee_is_nan(row(k))) exit
         nfield = k
      end do
   end subroutine read_fixed

   real(dp) function ieee_nan() result(x)
      use, intrinsic :: ieee_arithmetic, only: ieee_value, ieee_quiet_nan
      x = ieee_value(1.0_dp, ieee_quiet_nan)
   end function ieee_nan

   subroutine to_real(text, val, ios)
      character(len=*), intent(in) :: text
      real(dp), intent(out) :: val
      integer, intent(out) :: ios
      ios = 1
      val = 0.0_dp
      if (len_trim(text) == 0) return
      ! List-directed reads accept '1,2' or '1/': insist on a plain number
      if (verify(trim(adjustl(text)), '0123456789+-.eEdD') /= 0) then
         if (lower(trim(adjustl(text))) == 'nan' .or. lower(trim(adjustl(text))) == 'inf' &
             .or. lower(trim(adjustl(text))) == '-inf' .or. lower(trim(adjustl(text))) == 'infinity') then
            read (text, *, iostat=ios) val
         end if
         return
      end if
      read (text, *, iostat=ios) val
   end subroutine to_real

   !> How many of fields are numbers (blank ones not counted)
   integer function count_numeric(fields) result(n)
      character(len=*), intent(in) :: fields(:)
      integer :: k
      n = 0
      do k = 1, size(fields)
         if (len_trim(fields(k)) > 0 .and. all_numeric(fields(k:k))) n = n + 1
      end do
   end function count_numeric

   !> The first of fields that is not blank and not a number (0: none)
   integer function first_text(fields) result(k)
      character(len=*), intent(in) :: fields(:)
      do k = 1, size(fields)
         if (len_trim(fields(k)) > 0 .and. .not. all_numeric(fields(k:k))) return
      end do
      k = 0
   end function first_text

   logical function all_numeric(fields) result(ok)
      character(len=*), intent(in) :: fields(:)
      integer :: k, ios
      real(dp) :: val
      ok = .true.
      do k = 1, size(fields)
         if (len_trim(fields(k)) == 0) cycle
         call to_real(fields(k), val, ios)
         if (ios /= 0) then
            ok = .false.
            return
         end if
      end do
   end function all_numeric

   pure function joined(names) result(text)
      character(len=*), intent(in) :: names(:)
      character(len=:), allocatable :: text
      integer :: k
      text = ''
      do k = 1, size(names)
         if (k > 1) text = text//', '
         text = text//trim(adjustl(names(k)))
      end do
   end function joined

   !> Merge rows with the same time (column 1) into one by averaging, and check that time
   !> increases. Measured files repeat a time stamp where the logger wrote two samples at once.
   !> nmerged returns how many rows were folded into their predecessor.
   subroutine merge_repeated_times(values, file, nmerged, error)
      real(dp), allocatable, intent(inout) :: values(:, :)
      character(len=*), intent(in) :: file
      integer, intent(out) :: nmerged
      type(error_type), allocatable, intent(out) :: error
      integer :: i, m, cnt
      real(dp), allocatable :: out(:, :)
      allocate (out(size(values, 1), size(values, 2)))
      m = 1
      cnt = 1
      out(1, :) = values(1, :)
      nmerged = 0
      do i = 2, size(values, 1)
         if (values(i, 1) < values(i - 1, 1)) then
            call fatal_error(error, file//': time is not increasing at data row '//str(i)// &
               ' ('//str(values(i, 1))//' s after '//str(values(i - 1, 1))//' s)')
            return
         else if (values(i, 1) == out(m, 1)) then
            cnt = cnt + 1
            out(m, 2:) = out(m, 2:) + (values(i, 2:) - out(m, 2:))/real(cnt, dp)
            nmerged = nmerged + 1
         else
            m = m + 1
            cnt = 1
            out(m, :) = values(i, :)
         end if
      end do
      if (m < 3) then
         call fatal_error(error, file//': needs at least 3 distinct times, found '//str(m))
         return
      end if
      values = out(:m, :)
   end subroutine merge_repeated_times
end module usharp_table
