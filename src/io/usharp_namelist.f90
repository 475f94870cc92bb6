!> A namelist input file split into its groups, in one pass: each group's name, position and
!> lines, read later from those lines as an internal file. Anything the Fortran namelist read
!> would skip without a word is an error here: text outside a group (a group whose '&' is
!> missing), a group not closed by '/', an unknown group, a second copy of a group that a file
!> holds once. Shared by the readers of the groups (usharp_input_*).
module usharp_namelist
   use usharp_kinds, only: dp
   use usharp_error, only: error_type, fatal_error
   use usharp_strings, only: lower, str
   implicit none
   private

   public :: nml_file, nml_group, scan_namelist_file, find_group, group_text, group_error, read_error
   public :: check_length, dirname, resolve_path, string_value

   !> Longest character value a namelist variable holds; a longer value is an error, never cut
   integer, parameter, public :: value_len = 4096
   !> Longest list in a namelist array variable (levels, holds, fit, filter values)
   integer, parameter, public :: max_list = 64
   !> A real variable not given in the file
   real(dp), parameter, public :: unset = -huge(1.0_dp)

   !> One group of the file
   type :: nml_group
      character(len=16) :: name = ''               !< lower case, without '&'
      integer :: line = 0                          !< line of its '&'
      integer :: last = 0                          !< line of its end, '/'
      integer :: number = 0                        !< 1 for the first group of its name, 2 ...
   end type nml_group

   !> The file: its path, its folder (relative paths in it are relative to that) and groups
   type :: nml_file
      character(len=:), allocatable :: path
      character(len=:), allocatable :: base_dir
      type(nml_group), allocatable :: groups(:)
      character(len=:), allocatable :: text        !< the whole file
      integer, allocatable :: starts(:)            !< where each line starts in text
      !> Characters scanned (each line once) plus groups moved while the list grew: the
      !> scan's work, linear in the file's size (a test counts it)
      integer :: work = 0
   end type nml_file

contains

   !> Read path and split it into groups; known: the group names a file may hold, repeatable:
   !> those of them it may hold more than once
   subroutine scan_namelist_file(path, known, repeatable, file, error)
      character(len=*), intent(in) :: path
      character(len=*), intent(in) :: known(:), repeatable(:)
      type(nml_file), intent(out) :: file
      type(error_type), allocatable, intent(out) :: error
      integer, allocatable :: counts(:), firsts(:)
      integer :: nline, ngroup, l, a, b, col, k, open_line, quote_line
      character(len=1) :: quote
      character(len=:), allocatable :: word
      type(nml_group), allocatable :: tmp(:)
      logical :: inside

      call read_whole_file(path, file%text, error)
      if (allocated(error)) return
      file%path = path
      file%base_dir = dirname(path)
      call line_starts(file%text, file%starts)
      associate (text => file%text, starts => file%starts)
      nline = size(starts) - 1
      allocate (file%groups(16), counts(size(known)), firsts(size(known)))
      counts = 0
      firsts = 0
      ngroup = 0
      inside = .false.
      quote = ' '
      open_line = 0
      quote_line = 0
      do l = 1, nline
         a = starts(l)
         b = starts(l + 1) - 2   ! without the newline
         if (b >= a) then
            if (text(b:b) == achar(13)) b = b - 1
         end if
         col = a
         file%work = file%work + max(b - a + 1, 0) + 1
         if (.not. inside) then
            ! Between groups: blank lines and comments only, or the start of a group
            col = first_nonblank(text, a, b)
            if (col > b) cycle
            if (text(col:col) == '!') cycle
            if (text(col:col) /= '&') then
               call outside_error(text(col:b), l, col - a + 1)
               return
            end if
            word = group_word(text, col + 1, b)
            if (len(word) == 0 .or. word == 'end') then
               call outside_error(text(col:b), l, col - a + 1)
               return
            end if
            k = index_of(known, word)
            if (k == 0) then
               call fatal_error(error, path//':'//str(l)//':'//str(col - a + 1)// &
                  ': unknown namelist group &'//word//' (known: '//name_list(known)//')')
               return
            end if
            counts(k) = counts(k) + 1
            if (counts(k) == 1) then
               firsts(k) = l
            else if (index_of(repeatable, word) == 0) then
               call fatal_error(error, path//':'//str(l)//':'//str(col - a + 1)//': a second &'// &
                  word//' group (the first is at line '//str(firsts(k))//'); a file holds one')
               return
            end if
            ngroup = ngroup + 1
            if (ngroup > size(file%groups)) then
               ! Doubling keeps the scan linear in the number of groups
               allocate (tmp(2*size(file%groups)))
               tmp(:ngroup - 1) = file%groups(:ngroup - 1)
               file%work = file%work + ngroup - 1
               call move_alloc(tmp, file%groups)
            end if
            file%groups(ngroup)%name = word
            file%groups(ngroup)%line = l
            file%groups(ngroup)%number = counts(k)
            inside = .true.
            open_line = l
            col = col + 1 + len(word)
         else
            ! A line that starts a group inside a group: the group before lacks its '/'
            k = first_nonblank(text, a, b)
            if (quote == ' ' .and. k <= b) then
               if (text(k:k) == '&') then
                  word = group_word(text, k + 1, b)
                  if (len(word) > 0 .and. word /= 'end') then
                     call unterminated('; the next group starts at line '//str(l))
                     return
                  end if
               end if
            end if
         end if
         ! Inside a group: look for its end, '/' or &end outside quotes and comments
         call group_end(text, col, b, quote, k)
         if (quote /= ' ' .and. quote_line == 0) quote_line = l
         if (quote == ' ') quote_line = 0
         if (k == 0) cycle
         ! The group ends on this line; what follows on it must be a comment
         col = first_nonblank(text, k + 1, b)
         if (col <= b) then
            if (text(col:col) /= '!') then
               call fatal_error(error, path//':'//str(l)//':'//str(col - a + 1)// &
                  ': text after the end of &'//trim(file%groups(ngroup)%name)// &
                  " (one group per line, comments after '!')")
               return
            end if
         end if
         file%groups(ngroup)%last = l
         inside = .false.
      end do
      if (inside) then
         if (quote /= ' ') then
            call unterminated('; a quote opened on line '//str(quote_line)//' is not closed')
         else
            call unterminated('')
         end if
         return
      end if
      end associate
      file%groups = file%groups(:ngroup)
      file%work = file%work + ngroup
      do k = 1, ngroup
         call check_finite(file, k, error)
         if (allocated(error)) return
      end do

   contains

      subroutine outside_error(rest, line, column)
         character(len=*), intent(in) :: rest
         integer, intent(in) :: line, column
         character(len=:), allocatable :: first, hint
         integer :: e
         e = scan(rest, ' =,/!')
         if (e == 0) e = len(rest) + 1
         first = lower(rest(:e - 1))
         hint = ''
         if (index_of(known, first) > 0) hint = " (is '&' missing before "//first//'?)'
         call fatal_error(error, path//':'//str(line)//':'//str(column)// &
            ": text outside a namelist group, which starts with '&' and ends with '/'"//hint)
      end subroutine outside_error

      subroutine unterminated(why)
         character(len=*), intent(in) :: why
         call fatal_error(error, path//': &'//trim(file%groups(ngroup)%name)//' #'// &
            str(file%groups(ngroup)%number)//" is not terminated by '/'"//' (it starts at line '// &
            str(open_line)//why//')')
      end subroutine unterminated
   end subroutine scan_namelist_file

   !> The whole file as one string
   subroutine read_whole_file(path, text, error)
      character(len=*), intent(in) :: path
      character(len=:), allocatable, intent(out) :: text
      type(error_type), allocatable, intent(out) :: error
      integer :: unit, ios, nbytes
      logical :: exists
      character(len=512) :: msg
      inquire (file=path, exist=exists)
      if (.not. exists) then
         call fatal_error(error, path//': no such input file')
         return
      end if
      open (newunit=unit, file=path, status='old', action='read', access='stream', &
            form='unformatted', iostat=ios, iomsg=msg)
      if (ios /= 0) then
         call fatal_error(error, path//': cannot open ('//trim(msg)//')')
         return
      end if
      inquire (unit=unit, size=nbytes)
      allocate (character(len=max(nbytes, 0)) :: text)
      if (nbytes > 0) read (unit, iostat=ios, iomsg=msg) text
      close (unit)
      if (ios /= 0 .or. nbytes < 0) then
         call fatal_error(error, path//': cannot read ('//trim(msg)//')')
         return
      end if
   end subroutine read_whole_file

   !> Positions where each line starts, and one past the end (as if a newline ended the text)
   pure subroutine line_starts(text, starts)
      character(len=*), intent(in) :: text
      integer, allocatable, intent(out) :: starts(:)
      integer :: n, i
      n = 0
      do i = 1, len(text)
         if (text(i:i) == new_line('a')) n = n + 1
      end do
      if (len(text) > 0) then
         if (text(len(text):len(text)) /= new_line('a')) n = n + 1
      end if
      allocate (starts(n + 1))
      starts(1) = 1
      n = 1
      do i = 1, len(text)
         if (text(i:i) == new_line('a')) then
            n = n + 1
            starts(n) = i + 1
         end if
      end do
      ! A last line without a newline ends as if it had one
      if (n < size(starts)) starts(size(starts)) = len(text) + 2
   end subroutine line_starts

   pure integer function first_nonblank(text, a, b) result(k)
      character(len=*), intent(in) :: text
      integer, intent(in) :: a, b
      k = a
      do while (k <= b)
         if (text(k:k) /= ' ' .and. text(k:k) /= achar(9)) exit
         k = k + 1
      end do
   end function first_nonblank

   !> The lower-case name that starts at text(a:) (letters, digits, _)
   pure function group_word(text, a, b) result(word)
      character(len=*), intent(in) :: text
      integer, intent(in) :: a, b
      character(len=:), allocatable :: word
      integer :: e
      e = a
      do while (e <= b)
         if (verify(text(e:e), 'abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_') /= 0) exit
         e = e + 1
      end do
      word = lower(text(a:e - 1))
   end function group_word

   !> Scan text(a:b) of a group for its end, '/' or &end outside quotes and comments; quote
   !> carries an open quote across lines. k: position of the end's last character, 0 if none.
   pure subroutine group_end(text, a, b, quote, k)
      character(len=*), intent(in) :: text
      integer, intent(in) :: a, b
      character(len=1), intent(inout) :: quote
      integer, intent(out) :: k
      integer :: i
      k = 0
      i = a
      do while (i <= b)
         if (quote /= ' ') then
            if (text(i:i) == quote) quote = ' '   ! a doubled quote reopens at once
         else
            select case (text(i:i))
            case ("'", '"')
               quote = text(i:i)
            case ('!')
               return
            case ('/')
               k = i
               return
            case ('&')
               if (i + 3 <= b) then
                  if (lower(text(i + 1:i + 3)) == 'end') then
                     k = i + 3
                     return
                  end if
               end if
            end select
         end if
         i = i + 1
      end do
   end subroutine group_end

   !> No value of group k is NaN or infinite: Fortran's namelist read takes them as numbers,
   !> and a NaN passes every check of the form x < 0 (a hold of NaN s was taken as none). The
   !> error names the file, line, column, group and variable.
   pure subroutine check_finite(file, k, error)
      type(nml_file), intent(in) :: file
      integer, intent(in) :: k
      type(error_type), allocatable, intent(out) :: error
      character(len=1) :: quote
      character(len=:), allocatable :: variable, word
      integer :: l, a, b, i, j
      quote = ' '
      variable = '?'
      do l = file%groups(k)%line, file%groups(k)%last
         a = file%starts(l)
         b = file%starts(l + 1) - 2
         i = a
         if (l == file%groups(k)%line) i = index(file%text(a:max(a, b)), '&') + a + len_trim(file%groups(k)%name)
         do while (i <= b)
            if (quote /= ' ') then
               if (file%text(i:i) == quote) quote = ' '
               i = i + 1
               cycle
            end if
            select case (file%text(i:i))
            case ("'", '"')
               quote = file%text(i:i)
               i = i + 1
            case ('!')
               exit
            case (' ', ',', '=', '/', achar(9), achar(13), '(', ')', ':')
               i = i + 1
            case default
               ! A word: the variable's name when '=' follows it, else a value
               j = i
               do while (j < b)
                  if (scan(file%text(j + 1:j + 1), " ,=/!'()"//'"'//achar(9)//achar(13)) > 0) exit
                  j = j + 1
               end do
               word = lower(file%text(i:j))
               if (next_is_equals(j + 1, b)) then
                  variable = file%text(i:j)
               else
                  if (word(1:1) == '+' .or. word(1:1) == '-') word = word(2:)
                  if (index(word, '*') > 0) word = word(index(word, '*') + 1:)
                  if (word == 'nan' .or. word == 'inf' .or. word == 'infinity') then
                     call fatal_error(error, file%path//':'//str(l)//':'//str(i - a + 1)//': &'// &
                        trim(file%groups(k)%name)//': '//variable//' = '//file%text(i:j)// &
                        ' is not a number usharp can use')
                     return
                  end if
               end if
               i = j + 1
            end select
         end do
      end do

   contains

      !> Whether the next character after blanks from position p is '='
      pure logical function next_is_equals(p, last)
         integer, intent(in) :: p, last
         integer :: q
         next_is_equals = .false.
         do q = p, last
            if (file%text(q:q) == ' ' .or. file%text(q:q) == achar(9)) cycle
            next_is_equals = file%text(q:q) == '='
            return
         end do
      end function next_is_equals
   end subroutine check_finite

   !> The text value of variable (a quoted string) in the first group of that name, '' when
   !> the file has no such group or the group no such variable: for a look at a group this
   !> reader does not read whole (a constants file's &model name and units)
   pure function string_value(file, group, variable) result(value)
      type(nml_file), intent(in) :: file
      character(len=*), intent(in) :: group, variable
      character(len=:), allocatable :: value
      character(len=:), allocatable :: lines(:), low
      integer :: k, l, i, q
      character(len=1) :: mark
      value = ''
      k = find_group(file, lower(group))
      if (k == 0) return
      call group_text(file, k, lines)
      do l = 1, size(lines)
         low = lower(lines(l))
         i = index(low, lower(variable))
         do while (i > 0)
            ! The name alone (not the end of a longer one), then '=' and a quoted value
            if (i == 1) then
               q = i + len(variable)
            else if (scan(low(i - 1:i - 1), ' ,&') > 0) then
               q = i + len(variable)
            else
               q = 0
            end if
            if (q > 0) then
               q = q + verify(low(q:), ' ') - 1
               if (low(q:q) == '=') then
                  q = q + verify(low(q + 1:), ' ')
                  mark = lines(l)(q:q)
                  if (mark == "'" .or. mark == '"') then
                     value = lines(l)(q + 1:q + index(lines(l)(q + 1:), mark) - 1)
                     return
                  end if
               end if
            end if
            if (index(low(i + 1:), lower(variable)) == 0) exit
            i = i + index(low(i + 1:), lower(variable))
         end do
      end do
   end function string_value

   !> The lines of group k, from its '&' to its '/', as an internal file for the namelist read
   pure subroutine group_text(file, k, lines)
      type(nml_file), intent(in) :: file
      integer, intent(in) :: k
      character(len=:), allocatable, intent(out) :: lines(:)
      integer :: l, w, first, last
      first = file%groups(k)%line
      last = file%groups(k)%last
      w = 1
      do l = first, last
         w = max(w, file%starts(l + 1) - 1 - file%starts(l))
      end do
      allocate (character(len=w) :: lines(last - first + 1))
      do l = first, last
         lines(l - first + 1) = file%text(file%starts(l):min(file%starts(l + 1) - 2, len(file%text)))
         ! Tabs and carriage returns read as blanks
         call blank_controls(lines(l - first + 1))
      end do
   end subroutine group_text

   pure subroutine blank_controls(line)
      character(len=*), intent(inout) :: line
      integer :: i
      do i = 1, len(line)
         if (line(i:i) == achar(13) .or. line(i:i) == achar(9)) line(i:i) = ' '
      end do
   end subroutine blank_controls

   !> Position of word in names, 0 if absent (findloc is avoided: gfortran compares
   !> character values of different lengths without blank padding there)
   pure integer function index_of(names, word) result(k)
      character(len=*), intent(in) :: names(:), word
      do k = 1, size(names)
         if (names(k) == word) return
      end do
      k = 0
   end function index_of

   pure function name_list(names) result(text)
      character(len=*), intent(in) :: names(:)
      character(len=:), allocatable :: text
      integer :: i
      text = '&'//trim(names(1))
      do i = 2, size(names)
         text = text//', &'//trim(names(i))
      end do
   end function name_list

   !> Index of the first group called name, 0 if the file has none
   pure integer function find_group(file, name) result(k)
      type(nml_file), intent(in) :: file
      character(len=*), intent(in) :: name
      do k = 1, size(file%groups)
         if (file%groups(k)%name == name) return
      end do
      k = 0
   end function find_group

   !> An error of group: 'path: &group: text'
   pure subroutine group_error(error, path, group, text)
      type(error_type), allocatable, intent(out) :: error
      character(len=*), intent(in) :: path, group, text
      call fatal_error(error, path//': &'//group//': '//text)
   end subroutine group_error

   !> An error of the namelist read itself (an unknown variable, a value of the wrong type)
   pure subroutine read_error(error, path, group, ios, msg)
      type(error_type), allocatable, intent(out) :: error
      character(len=*), intent(in) :: path, group, msg
      integer, intent(in) :: ios
      call fatal_error(error, path//': &'//group//': '//trim(msg)//' (iostat '//str(ios)//')')
   end subroutine read_error

   !> A value that fills its whole buffer may have been cut: an error naming the variable
   !> and the limit. where: 'path: &group: '
   pure subroutine check_length(error, where, variable, value)
      type(error_type), allocatable, intent(inout) :: error
      character(len=*), intent(in) :: where, variable, value
      if (allocated(error)) return
      if (len_trim(value) >= len(value)) call fatal_error(error, where//variable// &
         ': the value is longer than '//str(len(value) - 1)//' characters, the longest usharp reads')
   end subroutine check_length

   !> Folder part of a path ('.' when none)
   pure function dirname(path) result(dir)
      character(len=*), intent(in) :: path
      character(len=:), allocatable :: dir
      integer :: k
      k = index(path, '/', back=.true.)
      if (k == 0) then
         dir = '.'
      else if (k == 1) then
         dir = '/'
      else
         dir = path(:k - 1)
      end if
   end function dirname

   !> A path relative to base unless absolute or empty; leading '../' steps are folded into
   !> base ('decks' + '../data/x' gives 'data/x')
   pure function resolve_path(base, path) result(full)
      character(len=*), intent(in) :: base, path
      character(len=:), allocatable :: full
      character(len=:), allocatable :: b, p
      if (len(path) == 0) then
         full = ''
         return
      else if (path(1:1) == '/') then
         full = path
         return
      end if
      b = base
      p = path
      do while (len(p) > 3 .and. b /= '.' .and. b /= '/')
         if (p(1:3) /= '../') exit
         if (b == '..' .or. index(b, '/..', back=.true.) == max(len(b) - 2, 1)) exit
         b = dirname(b)
         p = p(4:)
      end do
      if (b == '.') then
         full = p
      else if (b == '/') then
         full = '/'//p
      else
         full = b//'/'//p
      end if
   end function resolve_path

end module usharp_namelist
