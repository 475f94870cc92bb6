!> Tests of the data-table reader on small files and on the real Alloy 617 files
module test_table
   use testdrive, only: error_type, unittest_type, new_unittest, check, test_failed, skip_test
   use usharp_kinds, only: dp
   use usharp_error, only: uerror => error_type
   use usharp_table, only: read_columns, merge_repeated_times
   use usharp_filesys, only: check_text
   use usharp_strings, only: csv_field, split_fields, add_line, str, report_line_len
   use test_util, only: write_text, check_message
   implicit none
   private
   public :: collect_table

   character(len=*), parameter :: realdata = '../shared/realdata/a617-950C'

contains

   subroutine collect_table(testsuite)
      type(unittest_type), allocatable, intent(out) :: testsuite(:)
      testsuite = [ &
         new_unittest('csv-quoted-header-by-name-and-filter', test_csv), &
         new_unittest('whitespace-comment-header', test_whitespace), &
         new_unittest('byte-order-mark-of-a-spreadsheet', test_bom), &
         new_unittest('fixed-format', test_fixed), &
         new_unittest('bad-tables-rejected', test_bad), &
         new_unittest('row-of-other-field-count-rejected', test_field_count), &
         new_unittest('repeated-times-merged', test_merge), &
         new_unittest('long-line-and-no-final-newline', test_long_line), &
         new_unittest('real-a617-files-load', test_realdata), &
         new_unittest('csv-field-and-tab-separated-cells-read-back', test_csv_field), &
         new_unittest('report-lines-wrapped-and-long-words-cut', test_add_line)]
   end subroutine collect_table

   !> A field of the tables usharp writes, quoted when needed (a name with a comma would
   !> otherwise make a row of steps.csv five fields), reads back as one field, whole; a plain
   !> one stays bare
   subroutine test_csv_field(error)
      type(error_type), allocatable, intent(out) :: error
      character(len=64) :: fields(4)
      integer :: n
      call split_fields('x,'//csv_field('setup (data, problem)')//',3', fields, n)
      call check(error, n == 3 .and. fields(2) == 'setup (data, problem)' .and. fields(3) == '3', &
                 'the quoted field did not read back: '//csv_field('setup (data, problem)'))
      if (allocated(error)) return
      call check(error, csv_field('baseline') == 'baseline' .and. csv_field('a "b"') == '"a ""b"""', &
                 'plain or quoted field written wrongly')
      if (allocated(error)) return
      ! Tab-separated, as a spreadsheet exports an empty cell: four fields, the third empty;
      ! blanks alone: any run of them separates
      call split_fields('1.5'//achar(9)//'2'//achar(9)//achar(9)//' 4', fields, n)
      call check(error, n == 4 .and. fields(1) == '1.5' .and. fields(2) == '2' .and. &
                 len_trim(fields(3)) == 0 .and. fields(4) == '4', 'tab-separated row with an empty cell')
      if (allocated(error)) return
      call split_fields('  1.5   2  4', fields, n)
      call check(error, n == 3 .and. fields(3) == '4', 'blank-separated row')
   end subroutine test_csv_field

   !> Report lines: text longer than a line wrapped at a space, continuations indented by two
   !> spaces; a word longer than a line cut rather than wrapped without end; a value kept on
   !> the line of its name, a number with its percent sign
   subroutine test_add_line(error)
      type(error_type), allocatable, intent(out) :: error
      character(len=20) :: y18
      y18 = '  '//repeat('y', 18)
      call check_wrap(error, 'a table row | that stays', [character(len=20) :: 'a table row | that ', '  stays'], &
                      'wrapped at a space')
      if (allocated(error)) return
      call check_wrap(error, 'x '//repeat('y', 45), [character(len=20) :: 'x', y18, y18, '  '//repeat('y', 9)], &
                      'a long word after a space, cut')
      if (allocated(error)) return
      ! Not between a name and its value, nor before a percent sign
      call check_wrap(error, 'away: A1 = 1.2, B = 1.0E+12', [character(len=20) :: 'away: A1 = 1.2, ', &
                      '  B = 1.0E+12'], 'a value kept with its name')
      if (allocated(error)) return
      call check_wrap(error, 'the value 51.43219 % now', [character(len=20) :: 'the value ', '  51.43219 % now'], &
                      'a number kept with its percent sign')
      if (allocated(error)) return
      call check_table_row(error)
   end subroutine test_add_line

   !> In report lines, a Markdown table's row of 700 characters (a verdict naming five tests
   !> of long names) stays on one line, where prose of that length is wrapped
   subroutine check_table_row(error)
      type(error_type), allocatable, intent(out) :: error
      character(len=report_line_len), allocatable :: lines(:)
      character(len=:), allocatable :: row
      row = '| drift | '//repeat('lowers BIC, but ', 43)//'|'
      allocate (lines(0))
      call add_line(lines, row)
      call check(error, size(lines) == 1 .and. lines(1) == row, 'a table row of '//str(len(row))// &
                 ' characters wrapped onto '//str(size(lines))//' lines')
      if (allocated(error)) return
      call add_line(lines, row(3:))
      call check(error, size(lines) == 3, 'prose of '//str(len(row) - 2)//' characters not wrapped')
   end subroutine check_table_row

   !> text added to lines of 20 characters gives the lines expected
   subroutine check_wrap(error, text, expected, what)
      type(error_type), allocatable, intent(out) :: error
      character(len=*), intent(in) :: text, expected(:), what
      character(len=20), allocatable :: lines(:)
      allocate (lines(0))
      call add_line(lines, text)
      call check(error, size(lines), size(expected), 'lines: '//what)
      if (allocated(error)) return
      call check(error, all(lines == expected), what//': '//lines(1)//'/'//lines(size(lines)))
   end subroutine check_wrap

   subroutine test_csv(error)
      type(error_type), allocatable, intent(out) :: error
      real(dp), allocatable :: v(:, :)
      type(uerror), allocatable :: uerr
      character(len=:), allocatable :: path
      path = write_text('quoted.csv', [character(len=80) :: &
         '"Stress Mpa","Label","Elapsed Time Sec"', &
         '10.5,"Cycle 1",0.0', '12.0,"Cycle 1",1.0', '-3.0,"Cycle, 2",2.0', &
         '7.0,"Cycle 3",3.0', '8.0,"Cycle 1",4.0'])
      call read_columns(path, [character(len=32) :: 'elapsed time sec', 'Stress Mpa'], v, uerr, &
                        'Label', [character(len=16) :: 'Cycle 1', 'Cycle, 2'])
      if (allocated(uerr)) then
         call test_failed(error, uerr%message)
         return
      end if
      call check(error, size(v, 1), 4, 'rows kept by the filter')
      if (allocated(error)) return
      call check(error, v(3, 1), 2.0_dp, 'time of the quoted "Cycle, 2" row')
      if (allocated(error)) return
      call check(error, v(3, 2), -3.0_dp, 'stress picked by name')
      if (allocated(error)) return
      ! A filter value that no row holds (a typing error) is refused, not read as fewer rows
      call read_columns(path, [character(len=32) :: 'elapsed time sec', 'Stress Mpa'], v, uerr, &
                        'Label', [character(len=16) :: 'Cycle 1', 'Cycle 2'])
      call check(error, allocated(uerr), 'a filter value no row holds was taken')
      if (allocated(error)) return
      call check(error, index(uerr%message, "no row has 'Cycle 2' in column Label (it holds: Cycle 1, "// &
                 "Cycle, 2, Cycle 3)") > 0, uerr%message)
   end subroutine test_csv

   !> A comment longer than the line buffer (its rest passed over, the next record read whole),
   !> lines ended as on Windows (CR LF) and a last data row without a new line
   subroutine test_long_line(error)
      type(error_type), allocatable, intent(out) :: error
      real(dp), allocatable :: v(:, :)
      type(uerror), allocatable :: uerr
      character(len=:), allocatable :: path
      integer :: unit
      ! (the scratch folder made, then the file written whole here: a line too long for text lines)
      path = write_text('long.csv', [character(len=1) :: ''])
      open (newunit=unit, file=path, status='replace', action='write', access='stream', form='formatted')
      write (unit, '(a)') '# '//repeat('x', 5000)//' 9,9'
      write (unit, '(a)') 'time,stress'//achar(13)
      write (unit, '(a)') '0,1.5'
      write (unit, '(a)') '1,2.5'//achar(13)
      write (unit, '(a)', advance='no') '2,3.5'
      close (unit)
      call read_columns(path, [character(len=8) :: 'time', 'stress'], v, uerr)
      if (allocated(uerr)) then
         call test_failed(error, uerr%message)
         return
      end if
      call check(error, size(v, 1), 3, 'rows read')
      if (allocated(error)) return
      call check(error, v(2, 2), 2.5_dp, 'a row ended by CR LF')
      if (allocated(error)) return
      call check(error, v(3, 2), 3.5_dp, 'the last row, without a new line')
   end subroutine test_long_line

   subroutine test_whitespace(error)
      type(error_type), allocatable, intent(out) :: error
      real(dp), allocatable :: v(:, :)
      type(uerror), allocatable :: uerr
      character(len=:), allocatable :: path
      path = write_text('ws.txt', [character(len=80) :: '# produced by a test', &
         '# time strain stress', '0 0 0', '1  1e-4  2.25', '2 2e-4 4.5'])
      call read_columns(path, [character(len=8) :: 'stress', '1'], v, uerr)
      if (allocated(uerr)) then
         call test_failed(error, uerr%message)
         return
      end if
      call check(error, v(3, 1), 4.5_dp, 'stress by name from the comment header')
      if (allocated(error)) return
      call check(error, v(2, 2), 1.0_dp, 'time by position')
   end subroutine test_whitespace

   !> A spreadsheet's 'CSV UTF-8' (a byte order mark before the header): the first column
   !> found by its name
   subroutine test_bom(error)
      type(error_type), allocatable, intent(out) :: error
      real(dp), allocatable :: v(:, :)
      type(uerror), allocatable :: uerr
      character(len=:), allocatable :: path
      path = write_text('bom.csv', [character(len=80) :: &
         achar(239)//achar(187)//achar(191)//'time,strain,stress', '0,0,0', '1,1e-4,2.25', '2,2e-4,4.5'])
      call read_columns(path, [character(len=8) :: 'time', 'stress'], v, uerr)
      if (allocated(uerr)) then
         call test_failed(error, uerr%message)
         return
      end if
      call check(error, v(3, 1), 2.0_dp, 'time by name after the mark')
   end subroutine test_bom

   subroutine test_fixed(error)
      type(error_type), allocatable, intent(out) :: error
      real(dp), allocatable :: v(:, :)
      type(uerror), allocatable :: uerr
      character(len=:), allocatable :: path
      ! The original's files: E12.5 columns with no separator
      path = write_text('fixed.txt', [character(len=80) :: &
         ' 0.00000E+00-1.25000E+01', ' 1.00000E+00 1.30000E+01', ' 2.00000E+00-1.40000E+01'])
      call read_columns(path, [character(len=2) :: '1', '2'], v, uerr, fmt='(2E12.5)')
      if (allocated(uerr)) then
         call test_failed(error, uerr%message)
         return
      end if
      call check(error, v(1, 2), -12.5_dp, 'first stress')
      if (allocated(error)) return
      call check(error, v(3, 1), 2.0_dp, 'last time')
   end subroutine test_fixed

   subroutine test_bad(error)
      type(error_type), allocatable, intent(out) :: error
      integer :: nm
      real(dp), allocatable :: v(:, :)
      type(uerror), allocatable :: uerr
      character(len=:), allocatable :: path
      path = write_text('missingcol.csv', [character(len=40) :: 'time,stress', '0,1', '1,2', '2,3'])
      call read_columns(path, [character(len=8) :: 'time', 'strain'], v, uerr)
      call check_message(error, uerr, "no column 'strain' (columns: time, stress)")
      if (allocated(error)) return
      path = write_text('garbled.csv', [character(len=40) :: 'time,stress', '0,1', '1,abc', '2,3'])
      call read_columns(path, [character(len=8) :: 'time', 'stress'], v, uerr)
      call check_message(error, uerr, "garbled.csv:3:2: 'abc' in column stress is not a number")
      if (allocated(error)) return
      ! A file without a header whose first row has a value that is not a number: that row
      ! reads as a header, and the message says why, not only which names it holds
      path = write_text('noheader-bad.csv', [character(len=40) :: '0,1,abc', '1,2,3', '2,3,4', '3,4,5'])
      call read_columns(path, [character(len=8) :: 'time', 'stress'], v, uerr)
      call check_message(error, uerr, "noheader-bad.csv:1: no column 'time': this first row of values is "// &
                         "read as a header, as 'abc' in its column 3 is not a number")
      if (allocated(error)) return
      path = write_text('nan.csv', [character(len=40) :: 'time,stress', '0,1', '1,NaN', '2,3'])
      call read_columns(path, [character(len=8) :: 'time', 'stress'], v, uerr)
      call check_message(error, uerr, 'nan.csv:3:2: NaN in column stress is not finite')
      if (allocated(error)) return
      path = write_text('short.csv', [character(len=40) :: 'time,stress', '0,1', '1,2'])
      call read_columns(path, [character(len=8) :: 'time', 'stress'], v, uerr)
      call check_message(error, uerr, 'needs at least 3 data rows, found 2')
      if (allocated(error)) return
      path = write_text('back.csv', [character(len=40) :: 'time,stress', '0,1', '2,2', '1,3', '3,3'])
      call read_columns(path, [character(len=8) :: 'time', 'stress'], v, uerr)
      call merge_repeated_times(v, path, nm, uerr)
      call check_message(error, uerr, 'time is not increasing at data row 3')
      if (allocated(error)) return
      ! Read as a data file's time column: the line and column of the row, after a comment
      path = write_text('back2.csv', [character(len=40) :: '# rig log', 'stress,time', '1,0', &
                                      '2,2', '3,1', '3,3'])
      call read_columns(path, [character(len=8) :: 'time', 'stress'], v, uerr, time_first=.true.)
      call check_message(error, uerr, 'back2.csv:5:2: time is not increasing (1.00000 s after 2.00000 s)')
   contains
   end subroutine test_bad

   !> A row of more or fewer fields than the header names is refused, naming its line: decimal
   !> commas read as 1, 0, ... under the names time, strain, stress; empty last fields (a
   !> spreadsheet's trailing commas, on the rows or the header) are no extra fields
   subroutine test_field_count(error)
      type(error_type), allocatable, intent(out) :: error
      real(dp), allocatable :: v(:, :)
      type(uerror), allocatable :: uerr
      character(len=:), allocatable :: path
      path = write_text('decimal-comma.csv', [character(len=40) :: '# measured', &
         'time,strain,stress', '0.0,0.0,0.0', '1,0,1,0e-4,2,25', '2,0,2,0e-4,4,5'])
      call read_columns(path, [character(len=8) :: 'time', 'stress'], v, uerr)
      call check_message(error, uerr, 'decimal-comma.csv:4: row has 6 fields, the header names 3 '// &
                         '(decimal commas?')
      if (allocated(error)) return
      path = write_text('short-row.txt', [character(len=40) :: '# time strain stress', &
         '0 0 0', '1 2.25', '2 2e-4 4.5', '3 3e-4 6.75'])
      call read_columns(path, [character(len=8) :: 'time', 'strain'], v, uerr)
      call check_message(error, uerr, 'short-row.txt:3: row has 2 fields, the header names 3')
      if (allocated(error)) return
      path = write_text('no-header.txt', [character(len=40) :: '0 0 0', '1 1e-4 2.25 7', '2 2e-4 4.5'])
      call read_columns(path, [character(len=8) :: '1', '3'], v, uerr)
      call check_message(error, uerr, 'no-header.txt:2: row has 4 fields, the first row 3')
      if (allocated(error)) return
      path = write_text('trailing.csv', [character(len=40) :: 'time,strain,stress,temperature,', &
         '0,0,0,950,', '1,1e-4,2.25,,', '2,2e-4,4.5,', '3,3e-4,6.75,,,'])
      call read_columns(path, [character(len=8) :: 'time', 'stress'], v, uerr)
      if (allocated(uerr)) then
         call test_failed(error, 'empty last fields refused: '//uerr%message)
         return
      end if
      call check(error, v(4, 2), 6.75_dp, 'stress of the row with three empty last fields')
      if (allocated(error)) return
      ! One decimal comma in a file separated by blanks: the row is split at the comma alone
      path = write_text('blank-comma.txt', [character(len=40) :: 'time strain stress', &
         '0 0 0', '1 1e-4 2.25', '2 2e-4 4,5', '3 3e-4 6.75'])
      call read_columns(path, [character(len=8) :: 'time', 'stress'], v, uerr)
      call check_message(error, uerr, 'blank-comma.txt:4: row has 2 fields, the header names 3 '// &
                         '(decimal commas?')
      if (allocated(error)) return
      ! Files that are not text: UTF-16 (with and without its byte-order mark), lines ended by
      ! a carriage return alone
      call check_text('u16.txt', achar(255)//achar(254)//'t'//achar(0)//'i'//achar(0), uerr)
      call check_message(error, uerr, 'u16.txt: the file is in UTF-16; save it as UTF-8 or ASCII')
      if (allocated(error)) return
      call check_text('bin.txt', 't'//achar(0)//'i'//achar(0), uerr)
      call check_message(error, uerr, 'bin.txt: holds NUL bytes, not text')
      if (allocated(error)) return
      call check_text('cr.txt', 'time stress'//achar(13)//'0 1'//achar(13), uerr)
      call check_message(error, uerr, 'cr.txt: its lines end in a carriage return alone')
      if (allocated(error)) return
      call check_text('crlf.txt', 'time stress'//achar(13)//achar(10)//'0 1'//achar(13)//achar(10), uerr)
      call check(error, .not. allocated(uerr), 'CR LF line ends are text')
   end subroutine test_field_count

   subroutine test_merge(error)
      type(error_type), allocatable, intent(out) :: error
      real(dp), allocatable :: v(:, :)
      type(uerror), allocatable :: uerr
      integer :: nmerged
      v = reshape([0.0_dp, 1.0_dp, 1.0_dp, 2.0_dp, 10.0_dp, 20.0_dp, 30.0_dp, 40.0_dp], [4, 2])
      call merge_repeated_times(v, 'x', nmerged, uerr)
      call check(error, nmerged, 1, 'one repeated time')
      if (allocated(error)) return
      call check(error, v(2, 2), 25.0_dp, 'repeated rows averaged')
   end subroutine test_merge

   subroutine test_realdata(error)
      type(error_type), allocatable, intent(out) :: error
      real(dp), allocatable :: v(:, :)
      type(uerror), allocatable :: uerr
      logical :: exists
      integer :: nmerged
      inquire (file=realdata//'/lcf/HTM_A19_Cycles_435.csv', exist=exists)
      if (.not. exists) then
         call skip_test(error, 'measured data not found at '//realdata//' (shared/ not beside the checkout)')
         return
      end if
      call read_columns(realdata//'/lcf/HTM_A19_Cycles_435.csv', &
                        [character(len=24) :: 'Elapsed Time Sec', 'Stress Mpa', 'Strain'], v, uerr, &
                        'Cycle Label', [character(len=16) :: 'Cycle 1', 'Cycle 2'])
      if (.not. allocated(uerr)) call merge_repeated_times(v, 'lcf', nmerged, uerr)
      if (allocated(uerr)) then
         call test_failed(error, uerr%message)
         return
      end if
      ! Cycles 1 and 2 of sample 43-5 end at 12.28 s (a later cycle would extend the span)
      call check(error, v(size(v, 1), 1), 12.28_dp, 'end of cycle 2, s')
      if (allocated(error)) return
      call check(error, maxval(v(:, 3)), 0.00165_dp, 'largest strain in cycles 1-2', thr=1e-12_dp)
      if (allocated(error)) return
      call read_columns(realdata//'/creep/AirBase_950_19_a.csv', [character(len=8) :: 'time', 'strain'], v, uerr)
      if (.not. allocated(uerr)) call merge_repeated_times(v, 'creep', nmerged, uerr)
      if (allocated(uerr)) then
         call test_failed(error, uerr%message)
         return
      end if
      call check(error, size(v, 1) > 1000, 'creep curve rows')
      if (allocated(error)) return
      call read_columns(realdata//'/tensile/AirBase_950_D11.csv', [character(len=8) :: 'time', 'stress'], v, uerr)
      if (allocated(uerr)) then
         call test_failed(error, uerr%message)
         return
      end if
      call check(error, maxval(v(:, 2)) > 50.0_dp, 'tensile stress in MPa')
   end subroutine test_realdata
end module test_table
