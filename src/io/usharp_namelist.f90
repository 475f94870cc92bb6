!> A namelist input file split into its groups, in one pass: each group's name, position and
!> lines, read later from those lines as an internal file. Anything the Fortran namelist read
!> would skip without a word is an error here: text outside a group (a group whose '&' is
!> missing), a group not closed by '/', an unknown group, a second copy of a group that a file
!> holds once. Shared by the readers of the groups (usharp_input_*).
module usharp_namelist
   use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
   use usharp_kinds, only: dp
   use usharp_error, only: error_type, fatal_error
   use usharp_strings, only: lower, str
   use usharp_filesys, only: file_exists, read_whole_file, check_text
   implicit none
   private

   public :: nml_file, nml_group, scan_namelist_file, find_group, group_text, group_error, read_error
   public :: check_length, dirname, resolve_path, string_value, group_reader

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
      !> Where the quote is that the first line leaving one open opened (0: none)
      integer :: open_quote = 0
   end type nml_group

   abstract interface
      !> A group's namelist read from lines (an internal file) into values of its own
      subroutine group_reader(lines, ios, msg)
         character(len=*), intent(in) :: lines(:)
         integer, intent(out) :: ios
         character(len=*), intent(out) :: msg
      end subroutine group_reader
   end interface

   !> One assignment of a group (see group_items)
   type :: nml_item
      character(len=:), allocatable :: name        !< as written, with its subscript
      character(len=:), allocatable :: text        !< 'name = values', comments left out
      integer, allocatable :: at(:)                !< each character's place in the file
   end type nml_item

   !> The characters of a variable's name, and those it starts with
   character(len=*), parameter :: word_chars = &
      'abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_%'
   character(len=*), parameter :: letters = word_chars(:52)
   !> What a Fortran source's continuation mark in a namelist is told
   character(len=*), parameter :: ampersand_text = "a '&' does not continue a line in a "// &
      'namelist (its values go on over lines as they are): remove it'

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
      integer :: nline, ngroup, l, a, b, col, k, open_line, q
      character(len=1) :: quote
      character(len=:), allocatable :: word
      type(nml_group), allocatable :: tmp(:)
      logical :: inside

      if (.not. file_exists(path)) then
         call fatal_error(error, path//': no such input file')
         return
      end if
      call read_whole_file(path, file%text, error)
      if (.not. allocated(error)) call check_text(path, file%text, error)
      if (allocated(error)) return
      ! A UTF-8 byte-order mark (some editors write one) is no text, nor a column
      if (len(file%text) >= 3) then
         if (file%text(1:3) == achar(239)//achar(187)//achar(191)) file%text = file%text(4:)
      end if
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
                     call unterminated('; the next group starts at line '//str(l), l - 1)
                     return
                  end if
               end if
            end if
         end if
         ! Inside a group: look for its end, '/' or &end outside quotes and comments. A text
         ! value is written on one line: a quote left open ends with its line (carried on, it
         ! would take the groups after it into this one, up to a quote of theirs)
         call group_end(text, col, b, quote, k, q)
         if (quote /= ' ') then
            if (file%groups(ngroup)%open_quote == 0) file%groups(ngroup)%open_quote = q
            quote = ' '
         end if
         if (k == 0) cycle
         ! The group ends on this line; what follows on it must be a comment
         col = first_nonblank(text, k + 1, b)
         if (col <= b) then
            if (text(col:col) /= '!') then
               ! A '/' inside a value not in quotes (a path) ended the group there
               if (k == col - 1 .and. text(k:k) == '/' .and. text(col:col) /= '&') then
                  call fatal_error(error, path//':'//str(l)//':'//str(k - a + 1)//': &'// &
                     trim(file%groups(ngroup)%name)//": this '/' ends the group: text with a '/' in "// &
                     "it is a value in quotes (name = 'dir/file') or a comment after '!'")
                  return
               end if
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
         call unterminated('', nline)
         return
      end if
      end associate
      file%groups = file%groups(:ngroup)
      file%work = file%work + ngroup
      do k = 1, ngroup
         call check_values(file, k, error)
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

      !> The group begun at open_line has no end; a quote left open on one of its lines (a '/'
      !> after it was taken as text) is named too
      subroutine unterminated(why, last)
         character(len=*), intent(in) :: why
         !> the group's last line
         integer, intent(in) :: last
         character(len=:), allocatable :: quoted
         type(nml_item), allocatable :: items(:)
         integer :: m, p, pos
         quoted = ''
         if (file%groups(ngroup)%open_quote > 0) then
            ! Where the value's quotes begin to pair up wrongly, as for a group that ends
            pos = file%groups(ngroup)%open_quote
            file%groups(ngroup)%last = last
            call group_items(file, ngroup, items)
            do m = 1, size(items)
               if (.not. any(items(m)%at == file%groups(ngroup)%open_quote)) cycle
               p = open_quote(items(m))
               if (p > 0) pos = items(m)%at(p)
               exit
            end do
            quoted = '; the quotes from '//place(file, pos, .false.)//' do not pair up on their line'
         end if
         call fatal_error(error, path//': &'//trim(file%groups(ngroup)%name)//' #'// &
            str(file%groups(ngroup)%number)//" is not terminated by '/'"//' (it starts at line '// &
            str(open_line)//why//quoted//')')
      end subroutine unterminated
   end subroutine scan_namelist_file

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

   !> Scan text(a:b) of a group for its end, '/' or &end outside quotes and comments; quote:
   !> the quote open at the end (' ' if none), opened at position q. k: position of the
   !> end's last character, 0 if none.
   pure subroutine group_end(text, a, b, quote, k, q)
      character(len=*), intent(in) :: text
      integer, intent(in) :: a, b
      character(len=1), intent(inout) :: quote
      integer, intent(out) :: k, q
      integer :: i
      k = 0
      q = 0
      i = a
      do while (i <= b)
         if (quote /= ' ') then
            if (text(i:i) == quote) quote = ' '   ! a doubled quote reopens at once
         else
            select case (text(i:i))
            case ("'", '"')
               quote = text(i:i)
               q = i
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

   !> The assignments of group k in the order written: each variable's name (with its
   !> subscript, as written) and its text 'name = values' without comments, every character
   !> with its place in the file (0 for the blank that stands for a line break)
   pure subroutine group_items(file, k, items, stray)
      type(nml_file), intent(in) :: file
      integer, intent(in) :: k
      type(nml_item), allocatable, intent(out) :: items(:)
      !> where an '=' stands before the group's first assignment (0: none)
      integer, intent(out), optional :: stray
      character(len=1) :: quote, c
      character(len=:), allocatable :: name
      integer :: l, a, b, i, j, q, n
      type(nml_item), allocatable :: tmp(:)
      allocate (items(8))
      n = 0
      quote = ' '
      if (present(stray)) stray = 0
      lines: do l = file%groups(k)%line, file%groups(k)%last
         a = file%starts(l)
         b = file%starts(l + 1) - 2
         i = a
         if (l == file%groups(k)%line) i = index(file%text(a:max(a, b)), '&') + a + len_trim(file%groups(k)%name)
         ! A quote ends with its line, as the scan of the file has it
         quote = ' '
         do while (i <= b)
            c = file%text(i:i)
            if (quote /= ' ') then
               if (c == quote) quote = ' '
               if (n > 0) call add(items(n), i, i)
               i = i + 1
               cycle
            end if
            ! '&end' ends the group as '/' does
            if (c == '&' .and. i + 3 <= b) then
               if (lower(file%text(i:i + 3)) == '&end') then
                  if (i + 3 == b) exit lines
                  if (verify(file%text(i + 4:i + 4), word_chars) /= 0) exit lines
               end if
            end if
            select case (c)
            case ("'", '"')
               quote = c
               if (n > 0) call add(items(n), i, i)
               i = i + 1
            case ('!')
               exit
            case ('/')
               exit lines
            case ('a':'z', 'A':'Z')
               ! A letter inside a value (the exponent of 22.5e3, .true.) starts no name
               if (i > a) then
                  if (scan(file%text(i - 1:i - 1), word_chars//'.') > 0) then
                     if (n > 0) call add(items(n), i, i)
                     i = i + 1
                     cycle
                  end if
               end if
               j = i
               do while (j < b)
                  if (verify(file%text(j + 1:j + 1), word_chars) /= 0) exit
                  j = j + 1
               end do
               q = assigned_at(j + 1, b)
               if (q > 0) then
                  ! A variable's name (and subscript) followed by '=': a new assignment
                  name = file%text(i:j)//compact(file%text(j + 1:q - 1))
               else if (ends_line(j + 1, b) .and. .not. logical_word(file%text(i:j))) then
                  ! A name at the end of its line whose '=' starts a later line: an
                  ! assignment too (the '=' joins it as the characters after it do)
                  if (equals_next(l)) then
                     q = j
                     name = file%text(i:j)
                  end if
               end if
               if (q > 0) then
                  n = n + 1
                  if (n > size(items)) then
                     allocate (tmp(2*size(items)))
                     tmp(:n - 1) = items(:n - 1)
                     call move_alloc(tmp, items)
                  end if
                  items(n)%name = name
                  items(n)%text = ''
                  allocate (items(n)%at(0))
                  call add(items(n), i, q)
                  i = q + 1
               else
                  if (n > 0) call add(items(n), i, j)
                  i = j + 1
               end if
            case default
               if (n > 0) then
                  call add(items(n), i, i)
               else if (c == '=' .and. present(stray)) then
                  if (stray == 0) stray = i
               end if
               i = i + 1
            end select
         end do
         if (n > 0) call add(items(n), 0, 0)
      end do lines
      items = items(:n)

   contains

      !> Characters a to b of the file to an assignment (0, 0: a blank for a line end)
      pure subroutine add(item, a, b)
         type(nml_item), intent(inout) :: item
         integer, intent(in) :: a, b
         integer :: p
         if (a == 0) then
            item%text = item%text//' '
            item%at = [item%at, 0]
            return
         end if
         do p = a, b
            ! Tabs and carriage returns read as blanks
            if (file%text(p:p) == achar(9) .or. file%text(p:p) == achar(13)) then
               item%text = item%text//' '
            else
               item%text = item%text//file%text(p:p)
            end if
         end do
         item%at = [item%at, [(p, p=a, b)]]
      end subroutine add

      !> Whether the line holds nothing from p to last but blanks and a comment
      pure logical function ends_line(p, last) result(yes)
         integer, intent(in) :: p, last
         integer :: q
         q = first_nonblank(file%text, p, last)
         yes = q > last
         if (.not. yes) yes = file%text(q:q) == '!' .or. file%text(q:q) == achar(13)
      end function ends_line

      !> Whether the first character after line l, past blank and comment lines of the
      !> group, is '='
      pure logical function equals_next(l) result(yes)
         integer, intent(in) :: l
         integer :: m, q, e
         yes = .false.
         do m = l + 1, file%groups(k)%last
            e = file%starts(m + 1) - 2
            q = first_nonblank(file%text, file%starts(m), e)
            if (q > e) cycle
            if (file%text(q:q) == '!' .or. file%text(q:q) == achar(13)) cycle
            yes = file%text(q:q) == '='
            return
         end do
      end function equals_next

      !> Where the '=' is when a subscript (in parentheses) and blanks from p on lead to one
      !> on this line, else 0
      pure integer function assigned_at(p, last) result(q)
         integer, intent(in) :: p, last
         integer :: depth
         depth = 0
         do q = p, last
            select case (file%text(q:q))
            case (' ', achar(9))
            case ('(')
               depth = depth + 1
            case (')')
               depth = depth - 1
               if (depth < 0) exit
            case ('=')
               if (depth == 0) return
            case default
               if (depth == 0) exit
            end select
         end do
         q = 0
      end function assigned_at

      pure function compact(text) result(out)
         character(len=*), intent(in) :: text
         character(len=:), allocatable :: out
         integer :: p
         out = ''
         do p = 1, len(text)
            if (text(p:p) /= ' ' .and. text(p:p) /= achar(9)) out = out//text(p:p)
         end do
      end function compact
   end subroutine group_items

   !> 'path:line:column' of position p of the file's text ('line:column' when with_path is false)
   pure function place(file, p, with_path) result(text)
      type(nml_file), intent(in) :: file
      integer, intent(in) :: p
      logical, intent(in), optional :: with_path
      character(len=:), allocatable :: text
      integer :: l
      l = 1
      do while (l < size(file%starts) - 1)
         if (file%starts(l + 1) > p) exit
         l = l + 1
      end do
      text = str(l)//':'//str(p - file%starts(l) + 1)
      if (present(with_path)) then
         if (.not. with_path) return
      end if
      text = file%path//':'//text
   end function place

   !> The label of group k in messages: '&fit', '&test #2'
   pure function group_label(file, k) result(label)
      type(nml_file), intent(in) :: file
      integer, intent(in) :: k
      character(len=:), allocatable :: label
      label = '&'//trim(file%groups(k)%name)
      if (count(file%groups%name == file%groups(k)%name) > 1) label = label//' #'//str(file%groups(k)%number)
   end function group_label

   !> No value of group k is NaN or infinite (Fortran's namelist read takes them as numbers,
   !> and a NaN passes every check of the form x < 0: a hold of NaN s was taken as none), and
   !> no variable is given twice (the read keeps the last without a word). The error names the
   !> file, line, column, group and variable.
   pure subroutine check_values(file, k, error)
      type(nml_file), intent(in) :: file
      integer, intent(in) :: k
      type(error_type), allocatable, intent(out) :: error
      type(nml_item), allocatable :: items(:)
      character(len=1) :: quote
      character(len=:), allocatable :: word
      integer :: m, e, i, j, e2
      call group_items(file, k, items, i)
      if (i > 0) then
         call fatal_error(error, place(file, i)//': '//group_label(file, k)// &
            ": this '=' has no variable name before it; write each variable as name = value")
         return
      end if
      ! A text value is written on one line: quotes left open at a line's end (the read would
      ! take the line break and what follows into the text, or the '/' after it)
      if (file%groups(k)%open_quote > 0) then
         do m = 1, size(items)
            if (any(items(m)%at == file%groups(k)%open_quote)) exit
         end do
         if (m <= size(items)) then
            ! Placed where the value's quotes begin to pair up wrongly, as the read's error is
            i = open_quote(items(m))
            j = file%groups(k)%open_quote
            if (i > 0) j = items(m)%at(i)
            call fatal_error(error, place(file, j)//': '//group_label(file, k)// &
               ': '//items(m)%name//': the quotes here do not pair up on their line (a text value is '// &
               "written in quotes on one line: name = 'text')")
         else
            call fatal_error(error, place(file, file%groups(k)%open_quote)//': '//group_label(file, k)// &
               ': the quotes here do not pair up on their line')
         end if
         return
      end if
      do m = 1, size(items)
         do e = 1, m - 1
            if (lower(items(e)%name) == lower(items(m)%name)) then
               call fatal_error(error, place(file, items(m)%at(1))//': '//group_label(file, k)// &
                  ': '//items(m)%name//' is given twice (also at line:column '// &
                  place(file, items(e)%at(1), .false.)//'); give it once')
               return
            end if
         end do
         associate (text => items(m)%text)
            quote = ' '
            i = index(text, '=') + 1
            do while (i <= len(text))
               if (quote /= ' ') then
                  if (text(i:i) == quote) quote = ' '
                  i = i + 1
                  cycle
               end if
               if (text(i:i) == "'" .or. text(i:i) == '"') then
                  quote = text(i:i)
                  i = i + 1
               else if (scan(text(i:i), ' ,()') > 0) then
                  i = i + 1
               else if (text(i:i) == '=') then
                  ! An '=' after a value, not after a name (a name on the line before its '='
                  ! joins the value before it here): its variable's name is missing
                  j = len_trim(text(:i - 1))
                  if (j > 0) then
                     if (scan(text(j:j), word_chars) > 0) then
                        do while (j > 1)
                           if (scan(text(j - 1:j - 1), word_chars) == 0) exit
                           j = j - 1
                        end do
                     end if
                     e2 = len_trim(text(:i - 1))
                     if (verify(text(j:j), 'abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ)') /= 0 .or. &
                         logical_word(text(j:e2))) then
                        call fatal_error(error, place(file, items(m)%at(i))//': '//group_label(file, k)// &
                           ": this '=' has no variable name before it (after "//items(m)%name// &
                           '); write each variable as name = value')
                        return
                     end if
                  end if
                  i = i + 1
               else
                  ! A value: a number, a logical, or 'r*value'
                  j = i
                  do while (j < len(text))
                     if (scan(text(j + 1:j + 1), " ,()'"//'"') > 0) exit
                     j = j + 1
                  end do
                  word = lower(text(i:j))
                  if (index(word, '*') > 0) word = word(index(word, '*') + 1:)
                  if (len(word) > 0) then
                     if (word(1:1) == '+' .or. word(1:1) == '-') word = word(2:)
                  end if
                  if (word == 'nan' .or. word == 'inf' .or. word == 'infinity' .or. overflows(word)) then
                     call fatal_error(error, place(file, items(m)%at(i))//': '//group_label(file, k)// &
                        ': '//items(m)%name//' = '//text(i:j)//' is not a number usharp can use')
                     return
                  end if
                  i = j + 1
               end if
            end do
         end associate
      end do
   contains
      !> Whether word reads as a number beyond the largest double (1e400 reads as Infinity)
      pure logical function overflows(word) result(yes)
         character(len=*), intent(in) :: word
         real(dp) :: x
         integer :: ios
         yes = .false.
         if (verify(word, '0123456789.edqED+-') /= 0 .or. scan(word, '0123456789') == 0) return
         read (word, *, iostat=ios) x
         if (ios == 0) yes = .not. ieee_is_finite(x)
      end function overflows
   end subroutine check_values

   !> The text value of variable (a quoted string) in the first group of that name, '' when
   !> the file has no such group or the group no such variable: for a look at a group this
   !> reader does not read whole (a constants file's &model name and units)
   pure function string_value(file, group, variable) result(value)
      type(nml_file), intent(in) :: file
      character(len=*), intent(in) :: group, variable
      character(len=:), allocatable :: value
      type(nml_item), allocatable :: items(:)
      integer :: k, m, q
      character(len=1) :: mark
      value = ''
      k = find_group(file, lower(group))
      if (k == 0) return
      ! The assignments as the read takes them: comments out, a name whose '=' is on the
      ! next line in
      call group_items(file, k, items)
      do m = 1, size(items)
         if (lower(items(m)%name) /= lower(variable)) cycle
         associate (text => items(m)%text)
            q = index(text, '=')
            q = q + verify(text(q + 1:), ' ')
            if (q <= index(text, '=')) return
            mark = text(q:q)
            if (mark == "'" .or. mark == '"') then
               if (index(text(q + 1:), mark) > 0) value = text(q + 1:q + index(text(q + 1:), mark) - 1)
            end if
         end associate
         return
      end do
   end function string_value

   !> The lines of group k, from its '&' to its '/', as an internal file for the namelist read,
   !> without comments: gfortran's read takes 'a = 1.0, ! note' and a value on the next line
   !> for a null value between them (a list of three, the second unset)
   pure subroutine group_text(file, k, lines)
      type(nml_file), intent(in) :: file
      integer, intent(in) :: k
      character(len=:), allocatable, intent(out) :: lines(:)
      integer :: l, w, first, last, i
      character(len=1) :: quote
      first = file%groups(k)%line
      last = file%groups(k)%last
      w = 1
      do l = first, last
         w = max(w, file%starts(l + 1) - 1 - file%starts(l))
      end do
      allocate (character(len=w) :: lines(last - first + 1))
      do l = first, last
         associate (line => lines(l - first + 1))
            line = file%text(file%starts(l):min(file%starts(l + 1) - 2, len(file%text)))
            ! Tabs and carriage returns read as blanks
            call blank_controls(line)
            ! A comment, from '!' outside quotes (which end with their line) to the line's end
            quote = ' '
            do i = 1, len(line)
               if (quote /= ' ') then
                  if (line(i:i) == quote) quote = ' '
               else if (line(i:i) == "'" .or. line(i:i) == '"') then
                  quote = line(i:i)
               else if (line(i:i) == '!') then
                  line(i:) = ' '
                  exit
               end if
            end do
         end associate
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

   !> The number of values an assignment 'name = v1, v2 ...' gives: the words after its
   !> '=' between commas and blanks outside quotes
   pure integer function value_count(text) result(n)
      character(len=*), intent(in) :: text
      character :: quote
      logical :: inside
      integer :: i
      n = 0
      quote = ' '
      inside = .false.
      do i = index(text, '=') + 1, len(text)
         if (quote /= ' ') then
            if (text(i:i) == quote) quote = ' '
         else if (index(', '//achar(9), text(i:i)) > 0) then
            inside = .false.
         else
            if (.not. inside) n = n + 1
            inside = .true.
            if (text(i:i) == '''' .or. text(i:i) == '"') quote = text(i:i)
         end if
      end do
   end function value_count

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

   !> An error of the namelist read of group k (an unknown variable, a value of the wrong
   !> type), placed: the group's assignments are read again one at a time by reader, and the
   !> first that fails alone is named with its line and column. label: the group as messages
   !> name it, without its '&' (test #1 'lcf')
   subroutine read_error(error, file, k, label, ios, msg, reader)
      type(error_type), allocatable, intent(out) :: error
      type(nml_file), intent(in) :: file
      integer, intent(in) :: k, ios
      character(len=*), intent(in) :: label, msg
      procedure(group_reader) :: reader
      type(nml_item), allocatable :: items(:)
      character(len=512) :: why, why_quoted
      character(len=:), allocatable :: value, unknown, where, word, written, text
      integer :: m, stat, q
      logical :: colon
      allocate (items(0))
      if (k > 0) call group_items(file, k, items)
      do m = 1, size(items)
         call reader(['&'//trim(file%groups(k)%name)//' '//items(m)%text//' /'], stat, why)
         if (stat == 0) cycle
         value = shown_value(items(m))
         ! A quote the value opens and leaves open at its line's end: the rest of the group
         ! was read as text, so the read's words would name the wrong thing
         q = open_quote(items(m))
         if (q > 0) then
            call fatal_error(error, place(file, items(m)%at(q))//': &'//label//': '// &
               items(m)%name//': the quotes here do not pair up on their line (a text '// &
               "value is written in quotes on one line: name = 'text')")
            return
         end if
         ! More values than a list holds: the read's words name a value past the end
         q = value_count(items(m)%text)
         if (q > max_list) then
            call fatal_error(error, place(file, items(m)%at(1))//': &'//label//': '// &
               items(m)%name//': '//str(q)//' values, where a list holds at most '// &
               str(max_list))
            return
         end if
         ! A name without '=' after the value (it reads as part of the value)
         word = after(why, 'equal sign must follow namelist object name ')
         if (len(word) > 0) then
            q = word_at(items(m)%text, word)
            if (q > 0) then
               if (colon_assigns(items(m)%text, q, word)) then
                  call fatal_error(error, place(file, items(m)%at(q))//': &'//label//': '// &
                                   colon_message(items(m)%text(q:q + len(word) - 1)))
               else
                  call fatal_error(error, place(file, items(m)%at(q))//': &'//label//': '// &
                     word//" has no '=' after it; write each variable as name = value")
               end if
               return
            end if
         end if
         ! The read's words for a name it does not know (its words for a value it cannot read
         ! are often the same, naming the value: 'dt_out = abc' gives 'name abc')
         unknown = 'cannot match namelist object name '//lower(bare(items(m)%name))
         ! A word the read takes for a name, after the value: a stray word, or a name whose
         ! '=' is missing (not the value itself, which the read names so too)
         word = after(why, 'cannot match namelist object name ')
         if (len(word) > 0 .and. lower(trim(why)) /= unknown) then
            q = word_at(items(m)%text, word)
            ! (not the rest of a logical value, .true. where a number belongs)
            if (q > 1) then
               if (items(m)%text(q - 1:q - 1) == '.') q = 0
            end if
            if (q > 0) then
               if (len_trim(items(m)%text(index(items(m)%text, '=') + 1:q - 1)) > 0) then
                  if (colon_assigns(items(m)%text, q, word)) then
                     call fatal_error(error, place(file, items(m)%at(q))//': &'//label//': '// &
                                      colon_message(items(m)%text(q:q + len(word) - 1)))
                  else
                     call fatal_error(error, place(file, items(m)%at(q))//': &'//label//': '// &
                        word//" is neither a value of "//items(m)%name//" nor a variable with "// &
                        "its '='; write each variable as name = value")
                  end if
                  return
               end if
            end if
         end if
         ! A '&' that continues a line, as in Fortran source: the read takes it for a group's
         ! end ('&end')
         q = continuation_at(items(m))
         if (q > 0) then
            call fatal_error(error, place(file, items(m)%at(q))//': &'//label//': '// &
                             items(m)%name//': '//ampersand_text)
            return
         end if
         ! 'name: value' after the values of the assignment before it (the read took it
         ! for one of them)
         q = colon_name_at(items(m))
         if (q > 0) then
            word = items(m)%text(q:q + verify(items(m)%text(q:), word_chars) - 2)
            call fatal_error(error, place(file, items(m)%at(q))//': &'//label//': '// &
                             colon_message(word))
            return
         end if
         ! A text value without its quotes: the read takes it quoted
         text = trim(adjustl(items(m)%text(index(items(m)%text, '=') + 1:)))
         if (len(text) > 1) then
            if (text(len(text):) == ',') text = trim(text(:len(text) - 1))
         end if
         if (len(text) > 0 .and. scan(text, '''"') == 0) then
            call reader(['&'//trim(file%groups(k)%name)//' '//items(m)%name//" = '"//text// &
                         "' /"], stat, why_quoted)
            if (stat == 0) then
               call fatal_error(error, place(file, items(m)%at(1))//': &'//label//': '// &
                  items(m)%name//' = '//text//": a text value is written in quotes: "// &
                  items(m)%name//" = '"//text//"'")
               return
            end if
         end if
         if (lower(trim(why)) == unknown) then
            call fatal_error(error, place(file, items(m)%at(1))//': &'//label//': no variable '// &
               bare(items(m)%name)//' in this group (see the input reference)')
         else if (index(lower(why), 'cannot match namelist object name') > 0) then
            call fatal_error(error, place(file, items(m)%at(1))//': &'//label//': '//items(m)%name// &
               ' = '//value//' is not a value '//items(m)%name//' can take')
         else
            call fatal_error(error, place(file, items(m)%at(1))//': &'//label//': '//items(m)%name// &
               ' = '//value//' is not a value '//items(m)%name//' can take ('// &
               plain_reason(trim(why), bare(items(m)%name))//')')
         end if
         return
      end do
      ! No assignment fails alone (a name without '=', a stray word): the group's line, and
      ! for the first the form the read wants
      where = file%path
      if (k > 0) where = file%path//':'//str(file%groups(k)%line)
      word = after(msg, 'equal sign must follow namelist object name ')
      if (len(word) > 0) then
         ! The name's own place where an assignment holds it, or before the first one
         q = 0
         colon = .false.
         written = word
         do m = 1, size(items)
            q = word_at(items(m)%text, word)
            if (q > 0) then
               where = place(file, items(m)%at(q))
               colon = colon_assigns(items(m)%text, q, word)
               written = items(m)%text(q:q + len(word) - 1)
               exit
            end if
         end do
         if (q == 0) call leading_place(word, where, colon, written)
         if (colon) then
            call fatal_error(error, where//': &'//label//': '//colon_message(written))
         else
            call fatal_error(error, where//': &'//label//': '//word//" has no '=' after it; "// &
               'write each variable as name = value')
         end if
      else if (len(after(msg, 'cannot match namelist object name ')) > 0) then
         ! A word before the group's first assignment, placed where it stands
         word = after(msg, 'cannot match namelist object name ')
         colon = .false.
         written = word
         call leading_place(word, where, colon, written)
         if (colon) then
            call fatal_error(error, where//': &'//label//': '//colon_message(written))
         else
            call fatal_error(error, where//': &'//label//': '//word// &
               ' is no variable of this group with its value; write each variable as name = value')
         end if
      else
         ! A '&' before the first assignment: a continuation mark after the group's name
         q = 0
         if (k > 0) q = leading_word(file, k, '&')
         if (q > 0) then
            call fatal_error(error, place(file, q)//': &'//label//': '//ampersand_text)
         else
            call fatal_error(error, where//': &'//label//': '//plain_reason(trim(msg), '')// &
               ' (iostat '//str(ios)//')')
         end if
      end if
   contains
      !> Where word stands before the group's first assignment, whether it is given its value
      !> with ':' there, and the word as written there (each unchanged if it does not stand
      !> there)
      subroutine leading_place(word, where, colon, written)
         character(len=*), intent(in) :: word
         character(len=:), allocatable, intent(inout) :: where, written
         logical, intent(inout) :: colon
         integer :: at
         if (k == 0) return
         at = leading_word(file, k, word)
         if (at == 0) return
         where = place(file, at)
         colon = colon_assigns(file%text, at, word)
         written = file%text(at:at + len(word) - 1)
      end subroutine leading_place

      !> A variable's name without its subscript
      pure function bare(name) result(text)
         character(len=*), intent(in) :: name
         character(len=:), allocatable :: text
         text = name
         if (index(name, '(') > 1) text = name(:index(name, '(') - 1)
      end function bare

      !> The text of message after phrase (compared in lower case), its first word; '' when
      !> the message does not hold the phrase
      pure function after(message, phrase) result(rest)
         character(len=*), intent(in) :: message, phrase
         character(len=:), allocatable :: rest
         integer :: i
         rest = ''
         i = index(lower(message), phrase)
         if (i == 0) return
         rest = trim(adjustl(message(i + len(phrase):)))
         i = scan(rest, ' ,')
         if (i > 0) rest = rest(:i - 1)
      end function after
   end subroutine read_error

   !> An assignment's value for a message: its first line, at most 60 characters ('...' where
   !> cut), without the comma that ends it
   pure function shown_value(item) result(value)
      type(nml_item), intent(in) :: item
      character(len=:), allocatable :: value
      integer :: a, b
      logical :: cut
      a = index(item%text, '=') + 1
      b = len(item%text)
      cut = .false.
      if (any(item%at(a:b) == 0)) then
         ! (the blank that stands for the first line break after the '=')
         b = a - 2 + findloc(item%at(a:b), 0, 1)
         cut = len_trim(item%text(b + 1:)) > 0
      end if
      if (b - a + 1 > 60) then
         b = a + 59
         cut = .true.
      end if
      value = trim(adjustl(item%text(a:b)))
      if (len(value) > 1 .and. .not. cut) then
         if (value(len(value):) == ',') value = trim(value(:len(value) - 1))
      end if
      if (cut) value = value//' ...'
   end function shown_value

   !> When a quote in item's text is still open at its line's end (or the text's), or closes
   !> before a character that cannot follow a text value: where the first quote of that
   !> line's value is (the quotes pair up wrongly from there: 'a, b = 'c' leaves the last
   !> open), else 0; a doubled quote inside is one character
   pure integer function open_quote(item) result(q)
      type(nml_item), intent(in) :: item
      character(len=1) :: quote
      integer :: i, a
      q = 0
      quote = ' '
      a = index(item%text, '=') + 1
      i = a
      do while (i <= len(item%text))
         if (quote == ' ') then
            if (item%text(i:i) == "'" .or. item%text(i:i) == '"') then
               quote = item%text(i:i)
               q = i
            end if
         else if (item%at(i) == 0) then
            q = first_quote(q)
            return
         else if (item%text(i:i) == quote) then
            if (i < len(item%text)) then
               if (item%text(i + 1:i + 1) == quote) then
                  i = i + 2
                  cycle
               end if
            end if
            ! A text value ends at a blank, comma or '/': 'a, b='c' closes a quote before c
            if (i < len(item%text)) then
               if (scan(item%text(i + 1:i + 1), ' ,/') == 0) then
                  q = first_quote(q)
                  return
               end if
            end if
            quote = ' '
            q = 0
         end if
         i = i + 1
      end do
      if (q > 0) q = first_quote(q)
   contains
      !> The first quote of the value on the line of position p
      pure integer function first_quote(p) result(f)
         integer, intent(in) :: p
         f = p
         do while (f > a)
            if (item%at(f - 1) == 0) exit
            f = f - 1
         end do
         f = f - 1 + scan(item%text(f:p), '''"')
      end function first_quote
   end function open_quote

   !> Whether word is a logical value (T, F, true, false in any case), not a name
   pure logical function logical_word(word) result(yes)
      character(len=*), intent(in) :: word
      character(len=len(word)) :: w
      w = lower(word)
      yes = w == 't' .or. w == 'f' .or. w == 'true' .or. w == 'false'
   end function logical_word

   !> Where word (any case) stands alone in group k before its first assignment (outside
   !> comments), 0 if it does not
   pure integer function leading_word(file, k, word) result(q)
      type(nml_file), intent(in) :: file
      integer, intent(in) :: k
      character(len=*), intent(in) :: word
      type(nml_item), allocatable :: items(:)
      integer :: l, a, b, last, i
      call group_items(file, k, items)
      last = file%starts(file%groups(k)%last + 1) - 1
      if (size(items) > 0) last = items(1)%at(1) - 1
      q = 0
      do l = file%groups(k)%line, file%groups(k)%last
         a = file%starts(l)
         if (l == file%groups(k)%line) a = index(file%text(a:), '&') + a + len_trim(file%groups(k)%name)
         if (a > last) exit
         b = min(file%starts(l + 1) - 2, last)
         if (b < a) cycle
         if (index(file%text(a:b), '!') > 0) b = a + index(file%text(a:b), '!') - 2
         i = word_at('='//file%text(a:b), word)
         if (i > 0) then
            q = a + i - 2
            return
         end if
      end do
   end function leading_word

   !> Which characters of text lie inside a quoted value, its quotes included
   pure function quoted_mask(text) result(inside)
      character(len=*), intent(in) :: text
      logical :: inside(len(text))
      character(len=1) :: mark
      integer :: i
      mark = ' '
      do i = 1, len(text)
         inside(i) = mark /= ' '
         if (mark /= ' ') then
            if (text(i:i) == mark) mark = ' '
         else if (text(i:i) == '"' .or. text(i:i) == "'") then
            mark = text(i:i)
            inside(i) = .true.
         end if
      end do
   end function quoted_mask

   !> Where a '&' outside quotes is the first or the last thing on one of an assignment's
   !> lines, 0 if none is (a Fortran source's continuation mark)
   pure integer function continuation_at(item) result(q)
      type(nml_item), intent(in) :: item
      logical :: inside(len(item%text))
      integer :: i
      q = 0
      inside = quoted_mask(item%text)
      do i = 1, len(item%text)
         if (inside(i) .or. item%text(i:i) /= '&') cycle
         if (line_edge(i, 1) .or. line_edge(i, -1)) then
            q = i
            return
         end if
      end do
   contains
      !> Whether only blanks lie between i and its line's end (dir 1) or start (dir -1):
      !> the assignment's text ends there, or a line break joined in (at 0) comes first
      pure logical function line_edge(i, dir) result(yes)
         integer, intent(in) :: i, dir
         integer :: j
         j = i + dir
         do while (j >= 1 .and. j <= len(item%text))
            if (item%at(j) == 0) exit
            if (item%text(j:j) /= ' ') then
               yes = .false.
               return
            end if
            j = j + dir
         end do
         ! (the assignment's end is a line's end, or the next assignment follows; its
         ! start, the name, is no line's start)
         yes = dir > 0 .or. j >= 1
      end function line_edge
   end function continuation_at

   !> Where a name given its value with ':' stands among an assignment's values (outside
   !> quotes, not the value's first word, which may hold a ':' itself, as C:\x does), 0 if
   !> none does
   pure integer function colon_name_at(item) result(q)
      type(nml_item), intent(in) :: item
      logical :: inside(len(item%text))
      integer :: i, first, w
      q = 0
      first = index(item%text, '=') + 1
      if (first == 1) return
      first = first + verify(item%text(first:)//'x', ' ') - 1
      inside = quoted_mask(item%text)
      i = first
      do while (i <= len(item%text))
         if (.not. inside(i) .and. i > first .and. verify(item%text(i:i), letters) == 0 .and. &
             verify(item%text(i - 1:i - 1), word_chars//'.') /= 0) then
            ! a word that starts with a letter: its end, then a ':'?
            w = verify(item%text(i:)//' ', word_chars) - 1
            if (colon_assigns(item%text, i, item%text(i:i + w - 1))) then
               q = i
               return
            end if
            i = i + w
            cycle
         end if
         i = i + 1
      end do
   end function colon_name_at

   !> Whether the word at q of text is a name given its value with ':' ('name: value', as
   !> YAML and INI files write it): the word holds a ':', or a ':' is the next thing after it
   pure logical function colon_assigns(text, q, word) result(yes)
      character(len=*), intent(in) :: text, word
      integer, intent(in) :: q
      integer :: p, i
      yes = .false.
      if (len(word) == 0) return
      ! (the read takes 'name:' or "name:'text'" for one word; not a subscript's 'a(1:2)')
      i = index(word, ':')
      if (i > 1) yes = verify(word(:i - 1), word_chars) == 0
      ! (not a drive's 'c:\x' or a scheme's 'http://')
      if (yes .and. i < len(word)) yes = scan(word(i + 1:i + 1), '\/') == 0
      p = q + len(word)
      if (yes .or. p < 1 .or. p > len(text)) return
      i = verify(text(p:), ' '//achar(9))
      if (i == 0) return
      p = p + i - 1
      ! past a subscript: 'levels(1:2): ...'
      if (text(p:p) == '(' .and. index(text(p:), ')') > 0) then
         p = p + index(text(p:), ')')
         if (p > len(text)) return
         i = verify(text(p:), ' '//achar(9))
         if (i == 0) return
         p = p + i - 1
      end if
      yes = text(p:p) == ':'
   end function colon_assigns

   !> The message for a name given its value with ':' (see colon_assigns)
   pure function colon_message(word) result(text)
      character(len=*), intent(in) :: word
      character(len=:), allocatable :: text
      character(len=:), allocatable :: name
      name = word
      if (index(name, ':') > 1) name = name(:index(name, ':') - 1)
      text = name//": a namelist gives a value with '=', not ':'; write "//name//' = value'
   end function colon_message

   !> Where word (any case) stands alone in text after its first '=' and outside quotes, 0 if
   !> nowhere
   pure integer function word_at(text, word) result(q)
      character(len=*), intent(in) :: text, word
      logical :: inside(len(text))
      integer :: from, i
      inside = quoted_mask(text)
      from = index(text, '=') + 1
      do
         i = index(lower(text(from:)), lower(word))
         if (i == 0) then
            q = 0
            return
         end if
         q = from + i - 1
         if (alone(q - 1) .and. alone(q + len(word)) .and. .not. inside(q)) return
         from = q + 1
      end do
   contains
      pure logical function alone(p)
         integer, intent(in) :: p
         alone = .true.
         if (p < 1 .or. p > len(text)) return
         alone = verify(text(p:p), word_chars) /= 0
      end function alone
   end function word_at

   !> The namelist read's reason in plain words, for a value of variable (gfortran's words
   !> where it has none better): the first of reasons whose phrase the words hold, '@'
   !> standing for the variable
   pure function plain_reason(why, variable) result(text)
      character(len=*), intent(in) :: why, variable
      character(len=:), allocatable :: text
      character(len=*), parameter :: phrases(14) = [character(len=28) :: 'integer overflow', &
         'repeat count overflow', 'zero repeat count', 'misplaced = sign', 'qualifier for a scalar', &
         'out of range', 'bad data for namelist object', 'repeat count too large', 'bad integer', &
         'bad real', 'bad complex', 'bad logical', 'invalid string input', 'end of file']
      character(len=*), parameter :: reasons(14) = [character(len=76) :: &
         'beyond the range of a whole number, -2147483648 to 2147483647', 'a repeat count too large', &
         'a repeat count of 0', "an '=' where a value belongs", '@ takes no index', &
         'an index beyond the values @ holds', 'a value of another type than @ holds', &
         'more values than @ takes', 'not a whole number', 'not a number', 'not a number', &
         'not .true. or .false.', "a text value is written in quotes: name = 'text'", &
         "the group ends before its values do (a quote not closed, or a '/' missing)"]
      integer :: k, at
      text = why
      do k = 1, size(phrases)
         if (index(lower(why), trim(phrases(k))) == 0) cycle
         text = trim(reasons(k))
         at = index(text, '@')
         if (at > 0) text = text(:at - 1)//variable//text(at + 1:)
         return
      end do
   end function plain_reason

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
