!> Small string helpers
module usharp_strings
   use usharp_kinds, only: dp
   implicit none
   private

   public :: interval_end, interval_format
   public :: lower, str, real_str, split_fields, shell_quote, shell_word, gnuplot_string, pad, csv_field, join, add_line

   !> Length of a line of the program's reports and summaries: a Markdown table's row stays on
   !> one line up to it (a row wrapped ends the table). A refit's verdict takes up to 140
   !> characters for each test it makes worse: a row naming seven of 128-character names still
   !> wraps
   integer, parameter, public :: report_line_len = 1000
   !> Width at which prose is wrapped (see add_line)
   integer, parameter :: report_wrap = 400
   !> Characters enough for any real in any edit descriptor real_str is given (f0.d writes up
   !> to 309 digits before the point)
   integer, parameter :: real_buffer = 400

   !> Items joined into one line with a separator between them ('' for none)
   interface join
      module procedure :: join_words
      module procedure :: join_ints
   end interface join

   !> Text form of a number
   interface str
      module procedure :: str_int
      module procedure :: str_real
   end interface str

contains

   !> Append text to lines; prose longer than a line or than report_wrap is wrapped at a
   !> space, its continuation lines indented by two spaces (a paragraph to Markdown); a table
   !> row (text beginning with '|') only where longer than a line
   pure recursive subroutine add_line(lines, text)
      character(len=*), allocatable, intent(inout) :: lines(:)
      character(len=*), intent(in) :: text
      integer :: cut, width
      ! A table row is wrapped only where it would not fit the line
      width = len(lines)
      if (len(text) > 0) then
         if (text(1:1) /= '|') width = min(width, report_wrap)
      end if
      if (len(text) <= width) then
         lines = [character(len=len(lines)) :: lines, text]
         return
      end if
      cut = index(text(1:width), ' ', back=.true.)
      ! Not between a name and its value ("B = 1.030E+12") nor a number and its percent sign:
      ! the space before
      do while (cut > 2)
         if (.not. (scan(text(cut + 1:cut + 1), '=%') > 0 .or. text(cut - 1:cut - 1) == '=')) exit
         cut = index(text(1:cut - 1), ' ', back=.true.)
      end do
      ! (no space after a continuation's indent: cut the word, or the next call gets the same)
      if (cut <= 1 .or. (cut == 2 .and. text(1:2) == '  ')) cut = width
      lines = [character(len=len(lines)) :: lines, text(1:cut)]
      call add_line(lines, '  '//text(cut + 1:))
   end subroutine add_line

   !> Lower-case copy of a string (ASCII)
   pure function lower(text) result(res)
      character(len=*), intent(in) :: text
      character(len=len(text)) :: res
      integer :: i, ic
      res = text
      do i = 1, len(text)
         ic = iachar(text(i:i))
         if (ic >= iachar('A') .and. ic <= iachar('Z')) res(i:i) = achar(ic + 32)
      end do
   end function lower

   !> Words (their trailing blanks trimmed) joined with sep
   pure function join_words(w, sep) result(text)
      character(len=*), intent(in) :: w(:), sep
      character(len=:), allocatable :: text
      integer :: k
      text = ''
      do k = 1, size(w)
         if (k > 1) text = text//sep
         text = text//trim(w(k))
      end do
   end function join_words

   !> Integers joined with sep, as "1, 2, 3" for sep = ', '
   pure function join_ints(n, sep) result(text)
      integer, intent(in) :: n(:)
      character(len=*), intent(in) :: sep
      character(len=:), allocatable :: text
      integer :: k
      text = ''
      do k = 1, size(n)
         if (k > 1) text = text//sep
         text = text//str_int(n(k))
      end do
   end function join_ints

   ! The results below have their length given by a specification function, not deferred:
   ! gfortran 12 keeps a deferred-length result's length in a static variable at each call,
   ! which OpenMP threads calling the same line at once share (a wrong length, a torn text
   ! or a heap overrun); a length the caller computes is its own.

   !> Characters of an integer written with i0
   pure integer function int_width(val) result(w)
      integer, intent(in) :: val
      character(len=24) :: buf
      write (buf, '(i0)') val
      w = len_trim(buf)
   end function int_width

   !> Characters of real_str(val, fmt)
   pure integer function real_width(val, fmt) result(w)
      real(dp), intent(in) :: val
      character(len=*), intent(in) :: fmt
      character(len=real_buffer) :: buf
      call real_text(val, fmt, buf, w)
   end function real_width

   !> The text of real_str(val, fmt) in buf(:n) ('*' where fmt cannot write val)
   pure subroutine real_text(val, fmt, buf, n)
      real(dp), intent(in) :: val
      character(len=*), intent(in) :: fmt
      character(len=real_buffer), intent(out) :: buf
      integer, intent(out) :: n
      integer :: ios, k, dot, w
      call put_real(val, fmt, buf, n, ios)
      if (ios /= 0 .or. len(fmt) < 2 .or. n == 0) return
      ! An E or ES descriptor without an exponent width drops the letter for an exponent of
      ! three digits ('5.4329-167'): written again with one of three digits ('5.4329E-167')
      if (scan(fmt(1:1), 'eE') == 1 .and. scan(fmt(2:), 'eE') == 0 .and. scan(buf(:n), 'eE') == 0 &
          .and. scan(buf(:n), '0123456789') > 0) then
         ! two places wider for the third digit and the letter; the text is trimmed after
         k = verify(fmt, 'eEsSnN')
         dot = index(fmt, '.')
         w = 0
         if (k > 0 .and. dot > k) read (fmt(k:dot - 1), *, iostat=ios) w
         call put_real(val, fmt(:k - 1)//str_int(w + 2)//fmt(dot:)//'e3', buf, n, ios)
         return
      end if
      ! G0.d of a small or large value writes a mantissa below 1 and a bare exponent
      ! ('0.300000E-4'): written instead with d significant digits as 3.00000E-05
      if (len(fmt) > 3 .and. scan(fmt(1:1), 'gG') == 1 .and. fmt(2:3) == '0.' .and. &
          scan(buf(:n), 'eE') > 0) then
         read (fmt(4:), *, iostat=ios) w
         if (ios /= 0 .or. w < 1) return
         k = 2
         if (abs(val) >= 1.0e100_dp .or. abs(val) < 1.0e-99_dp) k = 3
         call put_real(val, 'es'//str_int(w + 8)//'.'//str_int(w - 1)//'e'//str_int(k), buf, n, ios)
         return
      end if
      if (scan(fmt(1:1), 'fF') /= 1) return
      ! A negative value that rounds to zero prints as zero ('-0.0' read as a loss where a
      ! share was zero to the digits shown)
      if (n > 1 .and. buf(1:1) == '-' .and. verify(buf(2:n), '0.') == 0) then
         buf = buf(2:n)
         n = n - 1
      end if
      if (fmt(2:2) /= '0') return
      if (buf(1:1) == '.') then
         buf = '0'//buf(:n)
         n = n + 1
      else if (n > 1 .and. buf(1:2) == '-.') then
         buf = '-0'//buf(2:n)
         n = n + 1
      end if
      if (buf(n:n) == '.') then
         buf(n:n) = ' '
         n = n - 1
      end if
   end subroutine real_text

   !> val in the descriptor f, left-adjusted, into buf(:n); '*' (and ios /= 0) where f cannot
   !> write it
   pure subroutine put_real(val, f, buf, n, ios)
      real(dp), intent(in) :: val
      character(len=*), intent(in) :: f
      character(len=real_buffer), intent(out) :: buf
      integer, intent(out) :: n, ios
      write (buf, '('//f//')', iostat=ios) val
      if (ios /= 0) then
         buf = '*'
         n = 1
      else
         buf = adjustl(buf)
         n = len_trim(buf)
      end if
   end subroutine put_real

   !> An integer as text (i0)
   pure function str_int(val) result(res)
      integer, intent(in) :: val
      character(len=int_width(val)) :: res
      write (res, '(i0)') val
   end function str_int

   !> A real as text (g0.6, trimmed)
   pure function str_real(val) result(res)
      real(dp), intent(in) :: val
      character(len=real_width(val, 'g0.6')) :: res
      res = real_str(val, 'g0.6')
   end function str_real

   !> Real number written with a given edit descriptor, trimmed. A zero-width F descriptor
   !> gets the leading zero the processor leaves out ('0.55', '-0.55', not '.55') and loses a
   !> bare trailing point ('6', not '6.').
   pure function real_str(val, fmt) result(res)
      real(dp), intent(in) :: val
      character(len=*), intent(in) :: fmt
      character(len=real_width(val, fmt)) :: res
      character(len=real_buffer) :: buf
      integer :: n
      call real_text(val, fmt, buf, n)
      res = buf(:n)
   end function real_str

   !> An end of a 95 % interval as text: 'open' where the data do not bound it (but 0, where a
   !> quantity that cannot be negative reaches its physical bound, as a number), else its value
   !> in the edit descriptor fmt
   pure function interval_end(val, unbounded, fmt) result(res)
      real(dp), intent(in) :: val
      logical, intent(in) :: unbounded
      character(len=*), intent(in) :: fmt
      character(len=:), allocatable :: res
      if (unbounded .and. abs(val) > 0.0_dp) then
         res = 'open'
      else
         res = trim(adjustl(real_str(val, fmt)))
      end if
   end function interval_end

   !> The edit descriptor for a value v and its interval [lo, hi]: three significant digits,
   !> more (up to six) where three would print an end of the interval as the value itself (a
   !> drag factor of 12.578 [12.567, 12.592] printed as 1.26E+01 [1.26E+01, 1.26E+01]); an
   !> end equal to the value (an end not bounded, given as the value) does not count
   pure function interval_format(v, lo, hi) result(fmt)
      real(dp), intent(in) :: v, lo, hi
      character(len=:), allocatable :: fmt
      character(len=:), allocatable :: text
      integer :: d
      do d = 3, 6
         fmt = 'es'//str(d + 6)//'.'//str(d - 1)
         text = real_str(v, fmt)
         if ((real_str(lo, fmt) /= text .or. .not. abs(lo - v) > 0.0_dp) .and. &
             (real_str(hi, fmt) /= text .or. .not. abs(hi - v) > 0.0_dp)) return
      end do
   end function interval_format

   !> Split a line into fields: by commas when the line holds one, else by tabs when it holds
   !> one (each separating one field from the next), else by runs of blanks.
   !> Double quotes group a field (a comma inside quotes does not split); quotes are removed.
   !> fields(:nfield) hold the fields (those beyond size(fields) dropped); the rest are undefined.
   pure subroutine split_fields(line, fields, nfield)
      character(len=*), intent(in) :: line
      character(len=*), intent(out) :: fields(:)
      integer, intent(out) :: nfield
      logical :: comma, inquote, infield
      integer :: i, k
      character :: c, sep
      ! Commas, else tabs, separate one field each (an empty cell is an empty field, as a
      ! spreadsheet exports it); without either, any run of blanks separates
      comma = has_unquoted_comma(line)
      sep = ','
      if (.not. comma .and. index(line, achar(9)) > 0) then
         comma = .true.
         sep = achar(9)
      end if
      ! Each field blanked as it starts, not all of them: a data file's rows use a few of the
      ! fields, and blanking every one took most of the time of reading a long file
      nfield = 0
      inquote = .false.
      infield = .false.
      k = 0
      do i = 1, len_trim(line)
         c = line(i:i)
         if (c == '"') then
            inquote = .not. inquote
            if (.not. infield) call start_field(fields, nfield, k, infield)
            cycle
         end if
         if (.not. inquote) then
            if (comma .and. c == sep) then
               if (.not. infield) call start_field(fields, nfield, k, infield)
               infield = .false.
               cycle
            else if (.not. comma .and. (c == ' ' .or. c == achar(9))) then
               infield = .false.
               cycle
            end if
         end if
         if (.not. infield) call start_field(fields, nfield, k, infield)
         if (nfield <= size(fields)) then
            k = k + 1
            if (k <= len(fields)) fields(nfield)(k:k) = c
         end if
      end do
      ! A trailing separator ends with an empty last field
      if (comma .and. len_trim(line) > 0) then
         if (line(len_trim(line):len_trim(line)) == sep) call start_field(fields, nfield, k, infield)
      end if
      if (comma) then
         do i = 1, min(nfield, size(fields))
            if (fields(i)(1:1) == ' ') fields(i) = adjustl(fields(i))
         end do
      end if
   end subroutine split_fields

   !> split_fields: the next field, blank, its length k 0
   pure subroutine start_field(fields, nfield, k, infield)
      character(len=*), intent(inout) :: fields(:)
      integer, intent(inout) :: nfield
      integer, intent(out) :: k
      logical, intent(out) :: infield
      nfield = nfield + 1
      k = 0
      infield = .true.
      if (nfield <= size(fields)) fields(nfield) = ''
   end subroutine start_field

   pure logical function has_unquoted_comma(line) result(found)
      character(len=*), intent(in) :: line
      logical :: inquote
      integer :: i
      found = .false.
      inquote = .false.
      do i = 1, len_trim(line)
         if (line(i:i) == '"') inquote = .not. inquote
         if (line(i:i) == ',' .and. .not. inquote) then
            found = .true.
            return
         end if
      end do
   end function has_unquoted_comma

   !> A text as a gnuplot single-quoted string: only a quote is special there, and doubled
   pure function gnuplot_string(text) result(quoted)
      character(len=*), intent(in) :: text
      character(len=:), allocatable :: quoted
      quoted = single_quoted(text, "''")
   end function gnuplot_string

   !> A text as one field of a CSV row (RFC 4180): as it is, or in double quotes with each
   !> quote doubled when it holds a comma, a quote or a line break (split_fields reads it back)
   pure function csv_field(text) result(field)
      character(len=*), intent(in) :: text
      character(len=:), allocatable :: field
      integer :: i
      if (scan(text, ',"'//new_line('a')//achar(13)) == 0) then
         field = text
         return
      end if
      field = '"'
      do i = 1, len(text)
         field = field//text(i:i)
         if (text(i:i) == '"') field = field//'"'
      end do
      field = field//'"'
   end function csv_field

   !> name blank-padded to width w (a longer name whole): a table's left-aligned column
   pure function pad(name, w) result(padded)
      character(len=*), intent(in) :: name
      integer, intent(in) :: w
      character(len=max(w, len(name))) :: padded
      padded = name
   end function pad

   !> A text quoted for the POSIX shell: in single quotes, each ' written as '\''
   pure function shell_quote(text) result(quoted)
      character(len=*), intent(in) :: text
      character(len=:), allocatable :: quoted
      quoted = single_quoted(text, "'\''")
   end function shell_quote

   !> A path as one word of a shell command line: quoted when it holds more than letters,
   !> digits and / . _ - + (a folder name with a blank)
   pure function shell_word(text) result(word)
      character(len=*), intent(in) :: text
      character(len=:), allocatable :: word
      if (verify(text, 'abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789/._-+') == 0) then
         word = text
      else
         word = shell_quote(text)
      end if
   end function shell_word

   !> A text in single quotes, each quote inside it written as escaped
   pure function single_quoted(text, escaped) result(quoted)
      character(len=*), intent(in) :: text, escaped
      character(len=:), allocatable :: quoted
      integer :: k
      quoted = "'"
      do k = 1, len(text)
         if (text(k:k) == "'") then
            quoted = quoted//escaped
         else
            quoted = quoted//text(k:k)
         end if
      end do
      quoted = quoted//"'"
   end function single_quoted
end module usharp_strings
