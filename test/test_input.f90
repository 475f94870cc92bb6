!> Bad input gives one clear line naming file, group and variable, and a non-zero exit
module test_input
   use testdrive, only: error_type, unittest_type, new_unittest, check, test_failed, skip_test
   use usharp_kinds, only: dp
   use usharp_error, only: uerror => error_type, stat_input, stat_io, stat_usage
   use usharp_config, only: run_config
   use usharp_namelist, only: nml_file, scan_namelist_file
   use usharp_input, only: known_groups
   use usharp_input, only: read_config, read_config_as
   use usharp_cmd_simulate, only: simulate_command
   use test_util, only: write_text, usharp_exe, read_text, scratch_dir, check_message
   implicit none
   private
   public :: collect_input, deck_lines

   character(len=*), parameter :: base_model = &
      "&model name='miller', units='ksi', temperature=866.15, tm=1800.0, youngs=22.5e3 /"
   character(len=*), parameter :: base_constants = &
      '&constants a1=0.8, a2=7.42e-5, b=1e15, c2=0.1, h1=280, h2=100, n=5.8, q=91000 /'

contains

   subroutine collect_input(testsuite)
      type(unittest_type), allocatable, intent(out) :: testsuite(:)
      testsuite = [ &
         new_unittest('missing-input-file', test_missing_file), &
         new_unittest('misspelled-variable', test_misspelled), &
         new_unittest('unknown-group-line-and-column', test_unknown_group), &
         new_unittest('unknown-history', test_unknown_history), &
         new_unittest('not-a-number-refused', test_not_finite), &
         new_unittest('constants-of-another-unit-refused', test_constants_units), &
         new_unittest('sizes-beyond-memory-refused', test_too_many_points), &
         new_unittest('unknown-jacobian', test_unknown_jacobian), &
         new_unittest('fit-lists-checked', test_fit_lists), &
         new_unittest('data-zero-throughout-refused', test_zero_data), &
         new_unittest('strain-in-percent-refused', test_percent_strain), &
         new_unittest('variable-without-equals-placed', test_no_equals), &
         new_unittest('namelist-read-reasons-in-plain-words', test_plain_reasons), &
         new_unittest('namelist-structure-placed', test_structure_placed), &
         new_unittest('external-backend-settings-checked', test_backend_settings), &
         new_unittest('unterminated-group', test_unterminated), &
         new_unittest('constant-not-positive', test_constant), &
         new_unittest('history-file-time-not-increasing', test_file_time), &
         new_unittest('history-file-empty-or-garbled', test_file_garbled), &
         new_unittest('history-file-columns-by-name', test_file_columns), &
         new_unittest('filter-and-its-column-together', test_filter_pair), &
         new_unittest('cyclic-rate-or-period', test_cyclic_rate_period), &
         new_unittest('data-format-checked-as-a-format', test_data_format), &
         new_unittest('unwritable-output-folder', test_unwritable), &
         new_unittest('simulate-writes-files', test_simulate_ok), &
         new_unittest('integrator-chosen-in-namelist', test_integrator_choice), &
         new_unittest('history-from-measured-strain-column', test_data_history), &
         new_unittest('measured-data-read-once-with-the-history', test_data_read_once), &
         new_unittest('thesis-data-reproducible-bit-for-bit', test_data_reproducible), &
         new_unittest('cli-exit-codes-and-one-line-errors', test_cli), &
         new_unittest('text-between-groups-is-an-error', test_text_between), &
         new_unittest('group-given-twice-is-an-error', test_group_twice), &
         new_unittest('test-names-are-unique', test_unique_names), &
         new_unittest('long-values-kept-whole-or-refused', test_long_values), &
         new_unittest('model-units-plausible', test_plausible_units), &
         new_unittest('reading-work-linear-in-groups', test_linear_reading), &
         new_unittest('namelist-reference-complete', test_reference_complete), &
         new_unittest('missing-fit-group-named', test_missing_fit), &
         new_unittest('list-longer-than-it-holds-named', test_long_list), &
         new_unittest('strain-in-percent-or-stress-in-a-smaller-unit-named', test_percent_strain_below_one)]
   end subroutine collect_input

   !> An input file of the model, the constants and the given extra lines
   function deck_lines(extra) result(lines)
      character(len=*), intent(in) :: extra(:)
      character(len=200), allocatable :: lines(:)
      lines = [character(len=200) :: base_model, base_constants, extra]
   end function deck_lines

   subroutine expect_config_error(error, name, extra, text)
      type(error_type), allocatable, intent(out) :: error
      character(len=*), intent(in) :: name, extra(:), text
      type(run_config) :: cfg
      type(uerror), allocatable :: uerr
      call read_config(write_text(name, deck_lines(extra)), cfg, uerr)
      call check_message(error, uerr, text)
   end subroutine expect_config_error

   subroutine test_missing_file(error)
      type(error_type), allocatable, intent(out) :: error
      type(run_config) :: cfg
      type(uerror), allocatable :: uerr
      call read_config('no/such/fit.nml', cfg, uerr)
      call check_message(error, uerr, 'no/such/fit.nml: no such input file')
      if (allocated(error)) return
      call check(error, uerr%stat, stat_input, 'input error category')
   end subroutine test_missing_file

   !> A misspelt name, a value of the wrong type and a variable given twice: each named with
   !> its line and column (the namelist read's own words named the value as a misspelt name,
   !> and took the last of two values without a word)
   subroutine test_misspelled(error)
      type(error_type), allocatable, intent(out) :: error
      call expect_config_error(error, 'misspelled.nml', [character(len=80) :: &
         "&test name='lcf', history='thesis_lcf', ampfirst=0.001 /"], &
         "misspelled.nml:3:41: &test #1 'lcf': no variable ampfirst in this group")
      if (allocated(error)) return
      call expect_config_error(error, 'bad-value.nml', [character(len=80) :: &
         "&test name='lcf', history='thesis_lcf',", "  dt_out = abc, sig = 14.0 /"], &
         "bad-value.nml:4:3: &test #1 'lcf': dt_out = abc is not a value dt_out can take")
      if (allocated(error)) return
      call expect_config_error(error, 'logical-value.nml', [character(len=80) :: &
         "&test name='lcf', history='thesis_lcf',", "  dt_out = .true. /"], &
         "logical-value.nml:4:3: &test #1 'lcf': dt_out = .true. is not a value dt_out can take")
      if (allocated(error)) return
      call expect_config_error(error, 'twice.nml', [character(len=80) :: &
         "&test name='lcf', history='thesis_lcf', dt_out = 1.0,", "  sig = 14.0, DT_OUT=2.0 /"], &
         "twice.nml:4:15: &test: DT_OUT is given twice (also at line:column 3:41)")
   end subroutine test_misspelled

   subroutine test_unknown_group(error)
      type(error_type), allocatable, intent(out) :: error
      call expect_config_error(error, 'group.nml', [character(len=80) :: &
         '&tset name="lcf" /'], 'group.nml:3:1: unknown namelist group &tset')
   end subroutine test_unknown_group

   subroutine test_unterminated(error)
      type(error_type), allocatable, intent(out) :: error
      call expect_config_error(error, 'unterminated.nml', [character(len=80) :: &
         "&test name='a', history='tensile', strain_rate=1e-4, final_strain=0.002 /", &
         "&test name='b', history='tensile', strain_rate=1e-4, final_strain=0.002"], &
         "unterminated.nml: &test #2 is not terminated by '/'")
   end subroutine test_unterminated

   subroutine test_unknown_history(error)
      type(error_type), allocatable, intent(out) :: error
      call expect_config_error(error, 'history.nml', [character(len=80) :: &
         "&test name='x', history='sawtooth' /"], "&test #1 'x': history = 'sawtooth' is not known")
   end subroutine test_unknown_history

   !> NaN and infinite values are refused where they are written, whatever the variable (a
   !> NaN passes x < 0 checks: a hold of NaN s was taken as none); text that merely holds
   !> 'nan' is a name, not a value
   subroutine test_not_finite(error)
      type(error_type), allocatable, intent(out) :: error
      call expect_config_error(error, 'nan-hold.nml', [character(len=80) :: &
         "&test name='x', history='cyclic', strain_range=0.01,", "  hold_max = NaN /"], &
         ": &test: hold_max = NaN is not a number usharp can use")
      if (allocated(error)) return
      call expect_config_error(error, 'inf-sig.nml', [character(len=80) :: &
         "&test name='nan', history='thesis_lcf', sig=-Infinity /"], &
         ": &test: sig = -Infinity is not a number usharp can use")
      if (allocated(error)) return
      call expect_config_error(error, 'nan-list.nml', [character(len=80) :: &
         "&test name='x', history='relaxation', levels = 0.001, nan /"], &
         "&test: levels = nan is not a number usharp can use")
   end subroutine test_not_finite

   !> Counts beyond what a simulation can hold are input errors, not crashes: cycles of two
   !> thousand million, and an output interval of 1e-9 s over a 240 s test
   subroutine test_too_many_points(error)
      type(error_type), allocatable, intent(out) :: error
      call expect_config_error(error, 'cycles.nml', [character(len=80) :: &
         "&test name='x', history='cyclic', strain_range=0.01, cycles=2000000000 /"], &
         "cyclic: cycles = 2000000000 is more than the 1250000 a history may have")
      if (allocated(error)) return
      call expect_config_error(error, 'dtout.nml', [character(len=80) :: &
         "&test name='x', history='thesis_lcf', dt_out=1e-9 /"], &
         "output times over the")
   end subroutine test_too_many_points

   !> A constants file that says its model and unit (a best.nml's &model line) is refused
   !> for a deck in another unit or of another model, and taken for its own
   subroutine test_constants_units(error)
      type(error_type), allocatable, intent(out) :: error
      type(run_config) :: cfg
      type(uerror), allocatable :: uerr
      character(len=:), allocatable :: deck, best
      deck = write_text('units-deck.nml', deck_lines([character(len=80) :: &
         "&test name='x', history='thesis_lcf' /"]))
      best = write_text('units-best.nml', [character(len=120) :: &
         "&model name = 'miller', units = 'MPa' /", &
         '&constants a1 = 0.116, a2 = 2.26e-7, b = 1e15, c2 = 0.69, h1 = 1930, h2 = 100, n = 5.8, q = 91000 /'])
      call read_config_as(deck, best, '', cfg, uerr)
      call check_message(error, uerr, "units-best.nml: &model: units = 'MPa', but the constants "// &
                         "are wanted in the deck's 'ksi'")
      if (allocated(error)) return
      best = write_text('units-best.nml', [character(len=120) :: &
         "&model name = 'miller', units = 'ksi' /", &
         '&constants a1 = 0.8, a2 = 7.42e-5, b = 1e15, c2 = 0.1, h1 = 280, h2 = 100, n = 5.8, q = 91000 /'])
      call read_config_as(deck, best, '', cfg, uerr)
      call check(error, .not. allocated(uerr), 'constants of the same unit taken')
   end subroutine test_constants_units

   subroutine test_unknown_jacobian(error)
      type(error_type), allocatable, intent(out) :: error
      call expect_config_error(error, 'jacobian.nml', [character(len=80) :: &
         "&fit fitted='B', method='lm', jacobian='exact' /", &
         "&test name='x', history='thesis_lcf' /"], &
         "&fit: jacobian = 'exact' is not known (difference, sensitivity)")
   end subroutine test_unknown_jacobian

   !> A constant named twice in fitted, a bound for a place fitted does not fill and a bad
   !> &fit setting are refused, each naming its variable
   subroutine test_fit_lists(error)
      type(error_type), allocatable, intent(out) :: error
      call expect_config_error(error, 'twice.nml', [character(len=80) :: &
         "&fit fitted='A1', 'A1', 'B', method='lm' /", &
         "&test name='x', history='thesis_lcf' /"], &
         "&fit: fitted names 'A1' twice")
      if (allocated(error)) return
      call expect_config_error(error, 'orphan.nml', [character(len=80) :: &
         "&fit fitted='A1', 'B', method='lm', upper(3)=7e4, box_lower(3)=1.0 /", &
         "&test name='x', history='thesis_lcf' /"], &
         "&fit: a bound (upper(3), box_lower(3)) is given for fitted constant 3, but fitted "// &
         "names 2 constants")
      if (allocated(error)) return
      call expect_config_error(error, 'starts.nml', [character(len=80) :: &
         "&fit fitted='A1', method='lm', multistart=-1 /", &
         "&test name='x', history='thesis_lcf' /"], &
         "&fit: multistart = -1 must be >= 0")
   end subroutine test_fit_lists

   !> A data column that is 0 at every row (a wrong column, an unconnected channel) is an
   !> input error naming the file and the column: the objective is relative to its peak, and
   !> every evaluation had failed, the fit ending on an error about the drag stress
   subroutine test_zero_data(error)
      use usharp_objective, only: fit_problem, setup_problem
      type(error_type), allocatable, intent(out) :: error
      type(run_config) :: cfg
      type(fit_problem) :: prob
      type(uerror), allocatable :: uerr
      character(len=:), allocatable :: data
      integer :: k
      character(len=40) :: rows(12)
      rows(1) = 'time,strain,stress'
      do k = 0, 10
         write (rows(k + 2), '(f6.1,a,es12.4,a)') real(k, dp), ',', 1.0e-4_dp*k, ',0.0'
      end do
      data = write_text('zero.csv', rows)
      call read_config(write_text('zero.nml', deck_lines([character(len=120) :: &
         "&fit fitted='B', method='lm' /", &
         "&test name='pull', history='data', data_file='zero.csv', dt_out=0.0 /"])), cfg, uerr)
      if (.not. allocated(uerr)) call setup_problem(cfg, prob, uerr)
      call check_message(error, uerr, "test 'pull': ")
      if (allocated(error)) return
      call check_message(error, uerr, "zero.csv: column 'stress' is 0 at every row: the "// &
                         "objective is relative to its peak")
      if (allocated(error)) return
      call check(error, uerr%stat, stat_input, 'an input error')
   end subroutine test_zero_data

   !> A measured strain column in percent (a 1.5 % test reaching 1.5) driving a test is an
   !> input error naming the file and the column; it had been simulated as 150 % strain
   subroutine test_percent_strain(error)
      type(error_type), allocatable, intent(out) :: error
      character(len=:), allocatable :: data
      integer :: k
      character(len=40) :: rows(12)
      rows(1) = 'time,strain,stress'
      do k = 0, 10
         write (rows(k + 2), '(f6.1,a,es12.4,a)') real(k, dp), ',', 0.15_dp*k, ',100.0'
      end do
      data = write_text('percent.csv', rows)
      call expect_config_error(error, 'percent.nml', [character(len=120) :: &
         "&test name='pull', history='data', data_file='percent.csv', dt_out=0.0 /"], &
         "percent.csv: column 'strain' reaches 1.500: strain is in mm/mm "// &
         "(is it in percent?)")
   end subroutine test_percent_strain

   !> A variable without its '=' is named at its line and column with the form the read wants
   subroutine test_no_equals(error)
      type(error_type), allocatable, intent(out) :: error
      call expect_config_error(error, 'noequals.nml', [character(len=80) :: &
         "&solver rtol 1.0e-7 /", "&test name='x', history='thesis_lcf' /"], &
         "noequals.nml:3:9: &solver: rtol has no '=' after it; write each variable as name = value")
      if (allocated(error)) return
      ! After a value, the name without '=' is placed itself (it had been read as part of the
      ! value before it, and the message named that variable)
      call expect_config_error(error, 'noequals2.nml', [character(len=80) :: &
         "&test name='lcf', history='thesis_lcf',", "  dt_out = 1.0", "  sig 14.0 /"], &
         "noequals2.nml:5:3: &test #1 'lcf': sig has no '=' after it; write each variable as "// &
         "name = value")
   end subroutine test_no_equals

   !> The namelist read's own words (gfortran's) put plainly: a number too large, more values
   !> than a variable takes, quotes that do not pair up on a line (the column of the line's
   !> first quote, not of the last, which the read found open, nor the rest of the group
   !> quoted as the value)
   subroutine test_plain_reasons(error)
      type(error_type), allocatable, intent(out) :: error
      call expect_config_error(error, 'overflow.nml', [character(len=80) :: &
         "&fit max_evals = 99999999999 /", "&test name='lcf', history='thesis_lcf' /"], &
         "overflow.nml:3:6: &fit: max_evals = 99999999999 is not a value max_evals can take "// &
         "(beyond the range of a whole number, -2147483648 to 2147483647)")
      if (allocated(error)) return
      ! A number beyond the largest double, which the read takes as Infinity
      call expect_config_error(error, 'infinite.nml', [character(len=80) :: &
         "&test name='lcf', history='thesis_lcf', dt_out = 1e400 /"], &
         "infinite.nml:3:50: &test: dt_out = 1e400 is not a number usharp can use")
      if (allocated(error)) return
      ! A stray word after a value is placed itself, not blamed on the variable before it
      call expect_config_error(error, 'stray.nml', [character(len=80) :: &
         "&test name='lcf', history='thesis_lcf',", "  dt_out = 1.0 foo /"], &
         "stray.nml:4:16: &test #1 'lcf': foo is neither a value of dt_out nor a variable with "// &
         "its '='; write each variable as name = value")
      if (allocated(error)) return
      call expect_config_error(error, 'repeat.nml', [character(len=80) :: &
         "&test name='lcf', history='thesis_lcf', dt_out = 2*1.0 /"], &
         "repeat.nml:3:41: &test #1 'lcf': dt_out = 2*1.0 is not a value dt_out can take "// &
         "(more values than dt_out takes)")
      if (allocated(error)) return
      call expect_config_error(error, 'pairs.nml', [character(len=80) :: &
         "&test name='lcf, history='thesis_lcf', dt_out = 1.0", "  sig = 14.0 ! the thesis's", "/"], &
         "pairs.nml:3:12: &test: name: the quotes here do not pair up on their line (a text "// &
         "value is written in quotes on one line: name = 'text')")
   end subroutine test_plain_reasons

   subroutine test_backend_settings(error)
      type(error_type), allocatable, intent(out) :: error
      call expect_config_error(error, 'backend.nml', [character(len=80) :: &
         "&test name='x', history='thesis_lcf', backend='ansys' /"], &
         "&test #1 'x': backend = 'ansys' is not known (internal or external)")
      if (allocated(error)) return
      call expect_config_error(error, 'nocommand.nml', [character(len=80) :: &
         "&test name='x', history='thesis_lcf', backend='external' /"], &
         "&test #1 'x': backend = 'external' needs command")
      if (allocated(error)) return
      call expect_config_error(error, 'outformat.nml', [character(len=90) :: &
         "&test name='x', history='thesis_lcf', backend='external', command='true',", &
         "  output_format='odb' /"], "output_format = 'odb' is not known (prvar or columns)")
      if (allocated(error)) return
      call expect_config_error(error, 'cformat.nml', [character(len=90) :: &
         "&test name='x', history='thesis_lcf', backend='external', command='true',", &
         "  constants_format='(A12)' /"], "constants_format = '(A12)' is not a Fortran format")
      if (allocated(error)) return
      call expect_config_error(error, 'timelimit.nml', [character(len=90) :: &
         "&test name='x', history='thesis_lcf', backend='external', command='true',", &
         "  time_limit=0 /"], 'time_limit must be > 0 s')
   end subroutine test_backend_settings

   subroutine test_constant(error)
      type(error_type), allocatable, intent(out) :: error
      type(run_config) :: cfg
      type(uerror), allocatable :: uerr
      character(len=200), allocatable :: lines(:)
      lines = deck_lines([character(len=80) :: "&test name='lcf', history='thesis_lcf' /"])
      lines(2) = '&constants a1=0.8, a2=7.42e-5, b=1e15, c2=0.1, h1=-280, h2=100, n=5.8, q=91000 /'
      call read_config(write_text('negative.nml', lines), cfg, uerr)
      call check_message(error, uerr, 'negative.nml: &constants: constant H1 must be > 0, got -280')
   end subroutine test_constant

   subroutine test_file_time(error)
      type(error_type), allocatable, intent(out) :: error
      character(len=:), allocatable :: hfile
      hfile = write_text('back.hist', [character(len=20) :: '0 0', '10 0.001', '5 0', '20 0'])
      call expect_config_error(error, 'backtime.nml', [character(len=80) :: &
         "&test name='f', history='file', file='back.hist' /"], &
         'back.hist:3:1: time is not increasing (5.00000 s after 10.0000 s)')
      if (allocated(error)) return
      call expect_config_error(error, 'nofile.nml', [character(len=80) :: &
         "&test name='f', history='file' /"], "&test #1 'f': history 'file' needs file")
   end subroutine test_file_time

   !> A list longer than a list variable holds is named as such, with the count
   subroutine test_long_list(error)
      type(error_type), allocatable, intent(out) :: error
      character(len=160) :: lines(6)
      integer :: i
      ! (over several lines, as a long list is written)
      lines(1) = "&test name='r', history='relaxation', levels="
      lines(2:) = ''
      do i = 1, 65
         write (lines(2 + (i - 1)/13)(len_trim(lines(2 + (i - 1)/13)) + 1:), '(es10.2,a)') &
            1.0e-5_dp*i, ','
      end do
      lines(6) = lines(6)(:len_trim(lines(6)) - 1)//' /'
      call expect_config_error(error, 'longlist.nml', lines, &
         "longlist.nml:3:39: &test #1 'r': levels: 65 values, where a list holds at most 64")
   end subroutine test_long_list

   !> A measured strain in percent below 1 (the thesis's LCF data, strain times 100, at most
   !> 0.5) passes the check of its size; the stiffness of its stretches tells it. So does a
   !> stress in MPa read as ksi (times 6.895, within the size check's bounds), under the
   !> measured strain and under the programmed one alike
   subroutine test_percent_strain_below_one(error)
      use usharp_objective, only: fit_problem, setup_problem
      type(error_type), allocatable, intent(out) :: error
      type(run_config) :: cfg
      type(fit_problem) :: prob
      type(uerror), allocatable :: uerr
      character(len=:), allocatable :: deck, programmed
      integer :: k
      deck = write_text('pct.nml', deck_lines([character(len=80) :: &
         "&fit fitted = 'H1' /", "&test name='lcf', history='data', data_file='pct.txt' /"]))
      programmed = write_text('pct-lcf.nml', deck_lines([character(len=80) :: &
         "&fit fitted = 'H1' /", "&test name='lcf', history='thesis_lcf', data_file='pct.txt' /"]))
      do k = 1, 5
         call write_data(merge(100.0_dp, 1.0_dp, k == 2), merge(6.895_dp, 1.0_dp, k >= 3))
         if (k >= 4) then
            call read_config(programmed, cfg, uerr)
         else
            call read_config(deck, cfg, uerr)
         end if
         if (.not. allocated(uerr)) call setup_problem(cfg, prob, uerr)
         select case (k)
         case (1)
            call check(error, .not. allocated(uerr), 'the strain in mm/mm passes')
         case (2)
            call check_message(error, uerr, "pct.txt: the stress rises with column 'strain' at "// &
                               'most 2.6')
            if (allocated(error)) return
            call check_message(error, uerr, 'is the strain in percent?')
         case (3, 4)
            call check_message(error, uerr, "pct.txt: column 'stress' rises with the strain by ")
            if (allocated(error)) return
            call check_message(error, uerr, "is the stress in another unit than data_unit = 'ksi'")
         case (5)
            ! The programmed history with the right stress: it passes
            call write_data(1.0_dp, 1.0_dp)
            call read_config(programmed, cfg, uerr)
            if (.not. allocated(uerr)) call setup_problem(cfg, prob, uerr)
            call check(error, .not. allocated(uerr), 'the programmed history with the data in ksi passes')
         end select
         if (allocated(error)) return
      end do
   contains
      !> The thesis's LCF data with the strain and the stress scaled, as pct.txt
      subroutine write_data(scale, stress_scale)
         real(dp), intent(in) :: scale, stress_scale
         real(dp) :: row(6)
         integer :: src, dst, ios
         character(len=400) :: line
         open (newunit=src, file='data/thesis/lcf.sim.txt', status='old', action='read')
         open (newunit=dst, file=scratch_dir//'/pct.txt', status='replace', action='write')
         write (dst, '(a)') 'time strain stress'
         do
            read (src, '(a)', iostat=ios) line
            if (ios /= 0) exit
            if (line(1:1) == '#') cycle
            read (line, *) row
            write (dst, '(3es24.15)') row(1), scale*row(2), stress_scale*row(3)
         end do
         close (src)
         close (dst)
      end subroutine write_data
   end subroutine test_percent_strain_below_one

   !> A fit of an input without &fit names the missing group, not an empty list of it
   subroutine test_missing_fit(error)
      use usharp_objective, only: fit_problem, setup_problem
      type(error_type), allocatable, intent(out) :: error
      type(run_config) :: cfg
      type(fit_problem) :: prob
      type(uerror), allocatable :: uerr
      call read_config(write_text('nofit.nml', deck_lines([character(len=80) :: &
         "&test name='r', history='relaxation', levels=0.00075, holds=60.0 /"])), cfg, uerr)
      if (allocated(uerr)) then
         call test_failed(error, uerr%message)
         return
      end if
      call setup_problem(cfg, prob, uerr)
      call check_message(error, uerr, 'nofit.nml: group &fit is missing')
   end subroutine test_missing_fit

   subroutine test_file_garbled(error)
      type(error_type), allocatable, intent(out) :: error
      character(len=:), allocatable :: hfile
      hfile = write_text('empty.hist', [character(len=20) :: '# nothing here'])
      call expect_config_error(error, 'empty.nml', [character(len=80) :: &
         "&test name='f', history='file', file='empty.hist' /"], &
         'empty.hist: needs at least 3 data rows, found 0')
      if (allocated(error)) return
      hfile = write_text('garbled.hist', [character(len=20) :: '0 0', '10 0.0x01', '20 0'])
      call expect_config_error(error, 'garbled.nml', [character(len=80) :: &
         "&test name='f', history='file', file='garbled.hist' /"], &
         "garbled.hist:2:2: '0.0x01' in column 2 is not a number")
   end subroutine test_file_garbled

   !> A history file with a header row is read by its column names: the stress column of a
   !> stress-controlled history (not the second column, the strain); a header without the
   !> column named is an error that lists the file's columns; bare numbers by position
   subroutine test_file_columns(error)
      type(error_type), allocatable, intent(out) :: error
      type(run_config) :: cfg
      type(uerror), allocatable :: uerr
      character(len=:), allocatable :: hfile
      hfile = write_text('named.hist', [character(len=30) :: 'time,strain,stress', '0,0,0', &
                         '10,0.0007,15', '1000,0.0034,15'])
      call read_config(write_text('named.nml', deck_lines([character(len=100) :: &
         "&test name='f', history='file', file='named.hist', control='stress' /"])), cfg, uerr)
      call check(error, .not. allocated(uerr), 'named history read')
      if (allocated(error)) return
      call check(error, maxval(cfg%tests(1)%hist%v) == 15.0_dp, 'the stress column commands the test')
      if (allocated(error)) return
      hfile = write_text('load.hist', [character(len=30) :: 'time,load', '0,0', '10,0.001', '20,0'])
      call expect_config_error(error, 'load.nml', [character(len=80) :: &
         "&test name='f', history='file', file='load.hist' /"], "load.hist: no column 'strain' (columns: time, load)")
      if (allocated(error)) return
      hfile = write_text('bare.hist', [character(len=30) :: '0 0', '10 0.001', '20 0'])
      call read_config(write_text('bare.nml', deck_lines([character(len=100) :: &
         "&test name='f', history='file', file='bare.hist' /"])), cfg, uerr)
      call check(error, .not. allocated(uerr), 'bare history read')
      if (allocated(error)) return
      call check(error, maxval(cfg%tests(1)%hist%v) == 0.001_dp, 'bare numbers by position')
   end subroutine test_file_columns

   !> filter without filter_column (all rows were read) and filter_column without filter
   subroutine test_filter_pair(error)
      type(error_type), allocatable, intent(out) :: error
      call expect_config_error(error, 'filter1.nml', [character(len=120) :: &
         "&test name='t', history='tensile', strain_rate=1e-4, final_strain=0.002, filter='Cycle 1' /"], &
         "filter needs filter_column")
      if (allocated(error)) return
      call expect_config_error(error, 'filter2.nml', [character(len=120) :: &
         "&test name='t', history='tensile', strain_rate=1e-4, final_strain=0.002, filter_column='Cycle' /"], &
         "filter_column = 'Cycle' needs filter")
   end subroutine test_filter_pair

   !> A data_format that is no Fortran format of numbers is named as such, not blamed on the
   !> data file's first line
   subroutine test_data_format(error)
      type(error_type), allocatable, intent(out) :: error
      call expect_config_error(error, 'badformat1.nml', [character(len=140) :: &
         "&test name='t', history='tensile', strain_rate=1e-4, final_strain=0.002, data_format='(3Q12.5)' /"], &
         "data_format = '(3Q12.5)' is not a Fortran format of numbers")
      if (allocated(error)) return
      call expect_config_error(error, 'badformat2.nml', [character(len=140) :: &
         "&test name='t', history='tensile', strain_rate=1e-4, final_strain=0.002, data_format='3E12.5' /"], &
         "data_format = '3E12.5' is not a Fortran format of numbers")
   end subroutine test_data_format

   !> cyclic with both strain_rate and period: refused (strain_rate had won, period ignored)
   subroutine test_cyclic_rate_period(error)
      type(error_type), allocatable, intent(out) :: error
      call expect_config_error(error, 'rateperiod.nml', [character(len=120) :: &
         "&test name='c', history='cyclic', strain_range=0.01, strain_rate=1e-3, period=100.0 /"], &
         "history 'cyclic' takes strain_rate or period, not both")
   end subroutine test_cyclic_rate_period

   subroutine test_unwritable(error)
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: uerr
      character(len=4096), allocatable :: written(:)
      character(len=:), allocatable :: path
      path = write_text('unwritable.nml', deck_lines([character(len=80) :: &
         "&test name='t', history='tensile', strain_rate=1e-4, final_strain=0.002 /"]))
      call simulate_command(path, '/proc/usharp-cannot-write-here', written, uerr)
      call check_message(error, uerr, '/proc/usharp-cannot-write-here: output folder cannot be created or written')
      if (allocated(error)) return
      call check(error, uerr%stat, stat_io, 'output error category')
   end subroutine test_unwritable

   subroutine test_simulate_ok(error)
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: uerr
      character(len=4096), allocatable :: written(:)
      character(len=:), allocatable :: path, text
      path = write_text('ok.nml', deck_lines([character(len=120) :: &
         "&test name='pull', history='tensile', strain_rate=1e-4, final_strain=0.002, dt_out=2 /", &
         "&test name='creep', history='creep', stress=15.0, ramp_time=1, duration=100 /"]))
      call simulate_command(path, scratch_dir//'/ok-out', written, uerr)
      if (allocated(uerr)) then
         call test_failed(error, uerr%message)
         return
      end if
      call check(error, size(written), 2, 'two files written')
      if (allocated(error)) return
      text = read_text(scratch_dir//'/ok-out/pull.sim.txt')
      call check(error, index(text, '# time strain stress eps_in back_stress drag_stress') > 0, &
                 'column header present')
   end subroutine test_simulate_ok

   !> history = 'data': the strain column of a measured Alloy 617 file drives the simulation
   subroutine test_data_history(error)
      use testdrive, only: skip_test
      use usharp_simulation, only: sim_result
      use usharp_simulate, only: simulate_test
      type(error_type), allocatable, intent(out) :: error
      type(run_config) :: cfg
      type(uerror), allocatable :: uerr
      type(sim_result) :: res
      character(len=*), parameter :: file = '../shared/realdata/a617-950C/lcf/HTM_A19_Cycles_435.csv'
      logical :: exists
      inquire (file=file, exist=exists)
      if (.not. exists) then
         call skip_test(error, 'measured data not found at '//file//' (shared/ not beside the checkout)')
         return
      end if
      ! The deck lives in build/test-scratch, so the file is three folders up
      call read_config(write_text('datahist.nml', deck_lines([character(len=200) :: &
         "&test name='a617', history='data', dt_out=0.5, data_file='../../"//file//"', ", &
         "time_column='Elapsed Time Sec', strain_column='Strain', filter_column='Cycle Label', ", &
         "filter='Cycle 1' /"])), cfg, uerr)
      if (.not. allocated(uerr)) call simulate_test(cfg%model, cfg%solver, cfg%tests(1), res, uerr)
      if (allocated(uerr)) then
         call test_failed(error, uerr%message)
         return
      end if
      ! The history's corners are the file's (time, strain) rows of cycle 1: ends at its last
      ! row and reaches the largest measured strain of cycle 1 (0.00159; 227 rows, 218 times)
      call check(error, size(cfg%tests(1)%hist%t), 218, 'one corner per distinct time of cycle 1')
      if (allocated(error)) return
      call check(error, maxval(cfg%tests(1)%hist%v), 0.00159_dp, 'largest strain of cycle 1', thr=1e-12_dp)
      if (allocated(error)) return
      call check(error, res%strain(size(res%t)), cfg%tests(1)%hist%v(size(cfg%tests(1)%hist%v)), &
                 'simulated strain follows the measured one to the end', thr=1e-15_dp)
   end subroutine test_data_history

   !> history = 'data': the compared stress (and weight) columns are read with the history,
   !> once: data written over after the input was read do not reach the comparison. A file
   !> without a stress column still drives a simulation, and a comparison names the column
   subroutine test_data_read_once(error)
      use usharp_experiment, only: experiment_type, load_experiment
      type(error_type), allocatable, intent(out) :: error
      type(run_config) :: cfg, cfg2
      type(uerror), allocatable :: uerr
      type(experiment_type) :: exp
      character(len=:), allocatable :: deck, csv
      character(len=60) :: rows(7)
      character(len=*), parameter :: weighted(2) = [character(len=40) :: "weighting='column', ", '']
      integer :: i, k
      ! With and without a weight column
      do k = 1, 2
         rows(1) = 'time,strain,Stress MPa,w'
         do i = 0, 5
            write (rows(i + 2), '(f4.1,a,es10.3,a,f6.2,a)') real(i, dp), ',', 1.0e-4_dp*i, ',', 2.0_dp*i, ',1'
         end do
         ! The time 2.0 twice: merged into one row of their mean
         rows(5) = ' 2.0, 3.000E-04,  5.00,3'
         csv = write_text('once.csv', rows)
         deck = write_text('once.nml', deck_lines([character(len=200) :: &
            "&test name='m', history='data', dt_out=1, data_file='once.csv', "//weighted(k), &
            "time_column='time', strain_column='strain', stress_column='Stress MPa', weight_column='w' /"]))
         call read_config(deck, cfg, uerr)
         if (.not. allocated(uerr)) then
            ! Other stresses written over the file after the input was read
            rows(2:) = [character(len=60) :: '0,0,9,1', '1,1e-4,9,1', '2,2e-4,9,1', '3,3e-4,9,1', &
                        '4,4e-4,9,1', '5,5e-4,9,1']
            csv = write_text('once.csv', rows)
            call load_experiment(cfg%tests(1), cfg%units, exp, uerr)
         end if
         if (allocated(uerr)) then
            call test_failed(error, uerr%message)
            return
         end if
         call check(error, size(exp%t) == 5 .and. exp%nmerged == 1, 'five distinct times, one row merged')
         if (allocated(error)) return
         call check(error, all(abs(exp%y - [0.0_dp, 2.0_dp, 4.5_dp, 8.0_dp, 10.0_dp]) < 1e-12_dp), &
                    'the stresses read with the history (merged at 2 s), '//trim(weighted(k)))
         if (allocated(error)) return
         if (k == 1) call check(error, all(abs(exp%weight - [1.0_dp, 1.0_dp, 2.0_dp, 1.0_dp, 1.0_dp]) &
                                           < 1e-12_dp), 'the weights read with the history (merged at 2 s)')
         if (allocated(error)) return
      end do
      ! No stress column: the history is read; the comparison says what is missing
      csv = write_text('once.csv', [character(len=20) :: 'time,strain', '0,0', '1,1e-4', '2,2e-4'])
      call read_config(deck, cfg2, uerr)
      if (allocated(uerr)) then
         call test_failed(error, 'a file without the stress column refused for its history: '//uerr%message)
         return
      end if
      call check(error, size(cfg2%tests(1)%hist%t) == 3, 'the history of three samples')
      if (allocated(error)) return
      call load_experiment(cfg2%tests(1), cfg2%units, exp, uerr)
      call check_message(error, uerr, "no column 'Stress MPa'")
   end subroutine test_data_read_once

   !> &solver integrator = 'umat' runs the single-element driver; an unknown one is an error
   subroutine test_integrator_choice(error)
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: uerr
      character(len=4096), allocatable :: written(:)
      character(len=:), allocatable :: text_u, text_c
      character(len=120), parameter :: pull = &
         "&test name='pull', history='tensile', strain_rate=1e-4, final_strain=0.003, dt_out=30 /"
      call simulate_command(write_text('umat.nml', deck_lines([character(len=120) :: &
         "&solver integrator='umat' /", pull])), scratch_dir//'/umat-out', written, uerr)
      if (.not. allocated(uerr)) call simulate_command(write_text('cvode.nml', deck_lines( &
         [character(len=120) :: pull])), scratch_dir//'/cvode-out', written, uerr)
      if (allocated(uerr)) then
         call test_failed(error, uerr%message)
         return
      end if
      text_u = read_text(scratch_dir//'/umat-out/pull.sim.txt')
      text_c = read_text(scratch_dir//'/cvode-out/pull.sim.txt')
      ! Different integrators, so the files differ (but both have the 11 rows of 0..300 s)
      call check(error, len(text_u) > 0 .and. text_u /= text_c, 'umat output differs from cvode output')
      if (allocated(error)) return
      call expect_config_error(error, 'badint.nml', [character(len=80) :: "&solver integrator='rk4' /", &
         "&test name='t', history='tensile', strain_rate=1e-4, final_strain=0.002 /"], &
         "&solver: integrator = 'rk4' is not known (cvode, rodas4 or umat)")
   end subroutine test_integrator_choice

   !> data/thesis and data/thesis-noise1 come back byte for byte from their decks (the
   !> 'regenerate' line differs only by the --out-dir given here)
   subroutine test_data_reproducible(error)
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: uerr
      character(len=4096), allocatable :: written(:)
      character(len=:), allocatable :: fresh, kept
      character(len=*), parameter :: sets(2) = ['thesis       ', 'thesis-noise1']
      character(len=*), parameter :: tests(3) = ['lcf    ', 'relax  ', 'ratchet']
      integer :: i, j
      do i = 1, 2
         call simulate_command('decks/'//trim(merge('thesis-data       ', 'thesis-data-noise1', i == 1))//'.nml', &
                               scratch_dir//'/'//trim(sets(i)), written, uerr)
         if (allocated(uerr)) then
            call test_failed(error, uerr%message)
            return
         end if
         do j = 1, 3
            fresh = without_line2(read_text(scratch_dir//'/'//trim(sets(i))//'/'//trim(tests(j))//'.sim.txt'))
            kept = without_line2(read_text('data/'//trim(sets(i))//'/'//trim(tests(j))//'.sim.txt'))
            call check(error, len(kept) > 1000 .and. fresh == kept, &
                       'data/'//trim(sets(i))//'/'//trim(tests(j))//'.sim.txt differs from its regeneration')
            if (allocated(error)) return
         end do
      end do
   contains
      function without_line2(text) result(rest)
         character(len=*), intent(in) :: text
         character(len=:), allocatable :: rest
         integer :: a, b
         a = index(text, new_line('a'))
         b = index(text(a + 1:), new_line('a')) + a
         rest = text(:a)//text(b + 1:)
      end function without_line2
   end subroutine test_data_reproducible

   !> The program itself: exit codes and one-line errors on stderr
   subroutine test_cli(error)
      type(error_type), allocatable, intent(out) :: error
      character(len=:), allocatable :: exe, errfile
      exe = usharp_exe()
      if (len(exe) == 0) then
         call skip_test(error, 'usharp executable not found beside the test program')
         return
      end if
      errfile = scratch_dir//'/stderr.txt'
      call expect_exit(exe, '', 2)
      if (allocated(error)) return
      call expect_exit(exe, 'frobnicate', 2)
      if (allocated(error)) return
      call expect_exit(exe, '--help', 0)
      if (allocated(error)) return
      call expect_exit(exe, '--version', 0)
      if (allocated(error)) return
      call expect_exit(exe, 'simulate --help', 0)
      if (allocated(error)) return
      call expect_exit(exe, 'simulate --version', 0)
      if (allocated(error)) return
      call expect_exit(exe, 'deck --help', 0)
      if (allocated(error)) return
      call expect_exit(exe, 'deck --version', 0)
      if (allocated(error)) return
      call expect_exit(exe, 'deck', 2)
      if (allocated(error)) return
      call expect_exit(exe, 'deck a b c.nml', 2)
      if (allocated(error)) return
      call expect_exit(exe, 'deck nosuch decks/thesis-data.nml -o '//scratch_dir//'/decks', stat_input)
      if (allocated(error)) return
      call check(error, read_text(errfile) == "usharp: error: decks/thesis-data.nml: no &test named 'nosuch'"// &
                 new_line('a'), 'deck of an unknown test: '//read_text(errfile))
      if (allocated(error)) return
      call expect_exit(exe, 'simulate no-such.nml', stat_input)
      if (allocated(error)) return
      call check(error, read_text(errfile) == 'usharp: error: no-such.nml: no such input file'//new_line('a'), &
                 'one line on stderr, no backtrace: '//read_text(errfile))
   contains
      subroutine expect_exit(exe, args, code)
         character(len=*), intent(in) :: exe, args
         integer, intent(in) :: code
         integer :: stat
         call execute_command_line(exe//' '//args//' > /dev/null 2> '//errfile, exitstat=stat)
         call check(error, stat, code, "exit code of 'usharp "//args//"'")
      end subroutine expect_exit
   end subroutine test_cli

   !> What the file's scan finds before the namelist read, at its own line and column: an '='
   !> with no name before it (not blamed on the variable before), a word before a group's
   !> first assignment on a line of its own, a quote left open on its line and a group after
   !> it (the quote had run on into that group, and the error named a '/' there); a UTF-8
   !> byte-order mark and a name whose '=' is on the next line are read as they are meant
   subroutine test_structure_placed(error)
      type(error_type), allocatable, intent(out) :: error
      character(len=*), parameter :: bom = achar(239)//achar(187)//achar(191)
      type(run_config) :: cfg, plain
      type(uerror), allocatable :: uerr
      call expect_config_error(error, 'equals.nml', [character(len=80) :: &
         "&test name='lcf', history='thesis_lcf', dt_out = 1.0", "  = 0.3 /"], &
         "equals.nml:4:3: &test: this '=' has no variable name before it (after dt_out); write each "// &
         "variable as name = value")
      if (allocated(error)) return
      call expect_config_error(error, 'leading.nml', [character(len=80) :: &
         "&test", "  lcf name='lcf', history='thesis_lcf' /"], &
         "leading.nml:4:3: &test #1: lcf is no variable of this group with its value; write each "// &
         "variable as name = value")
      if (allocated(error)) return
      call expect_config_error(error, 'runs-on.nml', [character(len=80) :: &
         "&test name='lcf, history='thesis_lcf' /", "&test name='b', history='thesis_lcf' /"], &
         "runs-on.nml: &test #1 is not terminated by '/' (it starts at line 3; the next group starts "// &
         "at line 4; the quotes from 3:12 do not pair up on their line)")
      if (allocated(error)) return
      ! 'name: value' (YAML, INI) after a value, first in the group, with a blank before the
      ! ':', and read as one word with a quoted value
      call expect_config_error(error, 'colon-after.nml', [character(len=80) :: &
         "&test name='lcf', history='thesis_lcf'", "  dt_out: 1.0 /"], &
         "colon-after.nml:4:3: &test #1 'lcf': dt_out: a namelist gives a value with '=', not ':'; write "// &
         "dt_out = value")
      if (allocated(error)) return
      call expect_config_error(error, 'colon-first.nml', [character(len=80) :: &
         "&test", "  name: 'lcf', history='thesis_lcf' /"], &
         "colon-first.nml:4:3: &test #1: name: a namelist gives a value with '=', not ':'")
      if (allocated(error)) return
      call expect_config_error(error, 'colon-blank.nml', [character(len=80) :: &
         "&test name='lcf', history='thesis_lcf'", "  dt_out : 1.0 /"], &
         "colon-blank.nml:4:3: &test #1 'lcf': dt_out: a namelist gives a value with '=', not ':'")
      if (allocated(error)) return
      call expect_config_error(error, 'colon-word.nml', [character(len=80) :: &
         "&test name='lcf'", "  history:'thesis_lcf' /"], &
         "colon-word.nml:4:3: &test #1 'lcf': history: a namelist gives a value with '=', not ':'")
      if (allocated(error)) return
      ! A '&' continuing a line, as in Fortran source (the read took it for '&end')
      call expect_config_error(error, 'ampersand.nml', [character(len=80) :: &
         "&test name='lcf', history='thesis_lcf', dt_out = 1.0, &", "  strain_rate = 1e-3 /"], &
         "ampersand.nml:3:55: &test #1 'lcf': dt_out: a '&' does not continue a line in a namelist")
      if (allocated(error)) return
      call expect_config_error(error, 'ampersand-inside.nml', [character(len=80) :: &
         "&test name='relax', history='thesis_relax', levels = 0.00075, &", &
         "  0.001, dt_out = 1.0 /"], &
         "ampersand-inside.nml:3:63: &test #1 'relax': levels: a '&' does not continue a line")
      if (allocated(error)) return
      ! ... after the values of a list (the read had named the list), and after a quoted
      ! value that holds the same words (the place had been the quoted one)
      call expect_config_error(error, 'colon-list.nml', [character(len=80) :: &
         "&test name='relax', history='thesis_relax',", "  levels = 0.00075, 0.001, dt_out: 1.0 /"], &
         "colon-list.nml:4:28: &test #1 'relax': dt_out: a namelist gives a value with '=', not ':'")
      if (allocated(error)) return
      call expect_config_error(error, 'colon-quoted.nml', [character(len=80) :: &
         "&test name='lcf', history='thesis_lcf', time_column = 'dt_out: x', dt_out: 1.0 /"], &
         "colon-quoted.nml:3:68: &test #1 'lcf': dt_out: a namelist gives")
      if (allocated(error)) return
      call expect_config_error(error, 'colon-subscript.nml', [character(len=80) :: &
         "&test name='relax', history='thesis_relax',", "  levels(1:2): 0.00075, 0.001 /"], &
         "colon-subscript.nml:4:3: &test #1 'relax': levels: a namelist gives a value with '='")
      if (allocated(error)) return
      call expect_config_error(error, 'ampersand-group.nml', [character(len=80) :: &
         "&test &", "  name='lcf', history='thesis_lcf' /"], &
         "ampersand-group.nml:3:7: &test #1: a '&' does not continue a line")
      if (allocated(error)) return
      ! A group ended by '&end' on its own line: the '&' is no continuation mark, and the
      ! last assignment's own fault is named
      call expect_config_error(error, 'ampersand-end.nml', [character(len=80) :: &
         "&test name='lcf', history='thesis_lcf', dt_out = 1.0, sigx = 14.0", "&end"], &
         "ampersand-end.nml:3:55: &test #1 'lcf': no variable sigx in this group")
      if (allocated(error)) return
      ! ... and '&end' after the last value on its line is no part of the value
      call expect_config_error(error, 'end-after-value.nml', [character(len=80) :: &
         "&test name='lcf', history = thesis_lcf &end"], &
         "end-after-value.nml:3:19: &test #1 'lcf': history = thesis_lcf: a text value is written "// &
         "in quotes: history = 'thesis_lcf'")
      if (allocated(error)) return
      ! A value holding a ':' (a path not in quotes) is no 'name: value'
      call expect_config_error(error, 'drive.nml', [character(len=80) :: &
         "&test name='lcf', history='thesis_lcf', dt_out = 1.0, data_file = C:\x.txt /"], &
         "drive.nml:3:55: &test #1 'lcf': data_file = C:\x.txt: a text value is written in quotes: "// &
         "data_file = 'C:\x.txt'")
      if (allocated(error)) return
      ! A text value without its quotes (the read had said only that it was no value)
      call expect_config_error(error, 'unquoted.nml', [character(len=80) :: &
         "&test name='lcf', history=thesis_lcf /"], &
         "unquoted.nml:3:19: &test #1 'lcf': history = thesis_lcf: a text value is written in "// &
         "quotes: history = 'thesis_lcf'")
      if (allocated(error)) return
      call expect_config_error(error, 'drive-after.nml', [character(len=80) :: &
         "&test name='lcf', history='thesis_lcf', data_file = 'a.txt' C:\x.txt /"], &
         "drive-after.nml:3:61: &test #1 'lcf': c:\x.txt is neither a value of data_file")
      if (allocated(error)) return
      ! A misspelt name with a subscript is named as a misspelt name
      call expect_config_error(error, 'subscript.nml', [character(len=80) :: &
         "&fit fitted = 'H1', uper(1:2) = 1.0, 2.0 /"], &
         "subscript.nml:3:21: &fit: no variable uper in this group")
      if (allocated(error)) return
      ! A path not in quotes: its '/' ends the group
      call expect_config_error(error, 'path.nml', [character(len=80) :: &
         "&test name='lcf', history='thesis_lcf', data_file = ../lcf.txt /"], &
         "path.nml:3:55: &test: this '/' ends the group: text with a '/' in it is a value in quotes")
      if (allocated(error)) return
      ! A text value over two lines (the read had taken the line break into the text)
      call expect_config_error(error, 'two-lines.nml', [character(len=80) :: &
         "&test name='lcf', history='thesis_", "  lcf', dt_out = 1.0", "/"], &
         "two-lines.nml:3:27: &test: history: the quotes here do not pair up on their line")
      if (allocated(error)) return
      call expect_config_error(error, 'two-lines-end.nml', [character(len=80) :: &
         "&test name='lcf', history='thesis_", "  lcf' /"], &
         "two-lines-end.nml: &test #1 is not terminated by '/' (it starts at line 3; the quotes from 3:27 "// &
         "do not pair up on their line)")
      if (allocated(error)) return
      ! A name whose '=' is on the next line is an assignment: given twice, and its value
      ! checked under its own name (they had been taken for the variable before)
      call expect_config_error(error, 'twice-next.nml', [character(len=80) :: &
         "&test name='lcf', history='thesis_lcf', dt_out = 1.0", "  dt_out", "  = 2.0 /"], &
         "twice-next.nml:4:3: &test: dt_out is given twice (also at line:column 3:41)")
      if (allocated(error)) return
      call expect_config_error(error, 'nan-next.nml', [character(len=80) :: &
         "&test name='lcf', history='thesis_lcf', sig = 14.0", "  dt_out", "  = nan /"], &
         "nan-next.nml:5:5: &test: dt_out = nan is not a number usharp can use")
      if (allocated(error)) return
      call read_config(write_text('next-line.nml', deck_lines([character(len=80) :: &
         "&test name='lcf', history='thesis_lcf', dt_out", "  = 2.0 /"])), cfg, uerr)
      call check(error, .not. allocated(uerr), 'a name with its = on the next line')
      if (allocated(error)) return
      call check(error, cfg%tests(1)%dt_out == 2.0_dp, 'dt_out read across the line')
      if (allocated(error)) return
      call read_config(write_text('bom.nml', [character(len=200) :: bom//base_model, base_constants, &
         "&test name='lcf', history='thesis_lcf' /"]), cfg, uerr)
      call check(error, .not. allocated(uerr), 'a byte-order mark before the first group')
      if (allocated(error)) return
      ! A comment after a list's comma, the list going on on the next line: the same history
      ! as the list on one line (the namelist read had put an unset level between them)
      call read_config(write_text('list-one-line.nml', deck_lines([character(len=80) :: &
         "&test name='r', history='relaxation', levels = 0.00075, 0.001,", &
         "  ramp_time = 1.0, holds = 600.0, 600.0 /"])), plain, uerr)
      call check(error, .not. allocated(uerr), 'the list on one line')
      if (allocated(error)) return
      call read_config(write_text('list-comment.nml', deck_lines([character(len=80) :: &
         "&test name='r', history='relaxation', levels = 0.00075,   ! first level", &
         "  0.001, ramp_time = 1.0, holds = 600.0, ! the first hold", "  600.0 /"])), cfg, uerr)
      call check(error, .not. allocated(uerr), 'a list with comments after its commas')
      if (allocated(error)) return
      call check(error, size(cfg%tests(1)%hist%t) == size(plain%tests(1)%hist%t), 'the same history')
      if (allocated(error)) return
      call check(error, all(cfg%tests(1)%hist%t == plain%tests(1)%hist%t) .and. &
                 all(cfg%tests(1)%hist%v == plain%tests(1)%hist%v), 'the same history')
      if (allocated(error)) return
      ! A constants file's units as the read takes them: not from a comment, and with the
      ! name's '=' on the next line
      call read_config_as(write_text('units-deck.nml', deck_lines([character(len=80) :: &
         "&test name='lcf', history='thesis_lcf' /"])), write_text('units-comment.nml', &
         [character(len=80) :: '&model', "  ! fitted before in MPa: units = 'MPa'", "  units = 'ksi' /", &
         base_constants]), '', cfg, uerr)
      call check(error, .not. allocated(uerr), 'a comment holding units = ''MPa'' in a ksi constants file')
      if (allocated(error)) return
      call read_config_as(write_text('units-deck.nml', deck_lines([character(len=80) :: &
         "&test name='lcf', history='thesis_lcf' /"])), write_text('units-next.nml', &
         [character(len=80) :: '&model', '  units', "  = 'MPa' /", base_constants]), '', cfg, uerr)
      call check(error, allocated(uerr), 'MPa constants (units, then = on the next line) for a ksi deck')
   end subroutine test_structure_placed

   !> A group whose '&' is missing, or any other text outside the groups, would be skipped by
   !> the namelist read (a test fewer, without a word): an error naming the line and column
   subroutine test_text_between(error)
      type(error_type), allocatable, intent(out) :: error
      character(len=*), parameter :: pull = &
         "&test name='a', history='tensile', strain_rate=1e-4, final_strain=0.002 /"
      call expect_config_error(error, 'nomark.nml', [character(len=90) :: pull, &
         "  ! a comment and a blank line are fine", "", &
         "test name='b', history='tensile', strain_rate=1e-4, final_strain=0.002 /"], &
         "nomark.nml:6:1: text outside a namelist group, which starts with '&' and ends with '/'"// &
         " (is '&' missing before test?)")
      if (allocated(error)) return
      call expect_config_error(error, 'stray.nml', [character(len=90) :: pull, "   use tests a and b"], &
         'stray.nml:4:4: text outside a namelist group')
      if (allocated(error)) return
      call expect_config_error(error, 'after.nml', [character(len=90) :: pull(:len(pull) - 1)// &
         "/ name='c' /"], 'after.nml:3:75: text after the end of &test')
      if (allocated(error)) return
      ! A group left open runs into the next one, or a quote left open to the end of the file
      call expect_config_error(error, 'open.nml', [character(len=90) :: pull(:len(pull) - 1), &
         "&test name='b', history='tensile', final_strain=0.002 /"], &
         "open.nml: &test #1 is not terminated by '/' (it starts at line 3; the next group starts at line 4)")
      if (allocated(error)) return
      call expect_config_error(error, 'quote.nml', [character(len=90) :: &
         "&test name='a, history='tensile', final_strain=0.002 /"], &
         "quote.nml: &test #1 is not terminated by '/' (it starts at line 3; the quotes from 3:12 do not pair "// &
         "up on their line)")
   end subroutine test_text_between

   !> A second copy of a group the file holds once would be ignored: an error at its line
   subroutine test_group_twice(error)
      type(error_type), allocatable, intent(out) :: error
      character(len=*), parameter :: pull = &
         "&test name='a', history='tensile', strain_rate=1e-4, final_strain=0.002 /"
      character(len=90) :: groups(7), lines(5)
      integer :: i
      type(run_config) :: cfg
      type(uerror), allocatable :: uerr
      groups = [character(len=90) :: base_model, base_constants, '&solver /', '&output /', &
                "&fit fitted = 'B' /", '&design /', '&diagnose /']
      do i = 1, size(groups)
         ! model, constants, the group (a test for model and constants), a test, the group again
         ! (element by element: gfortran 12 miscompiles such a mixed array constructor)
         lines(1) = base_model
         lines(2) = base_constants
         lines(3) = groups(i)
         if (i <= 2) lines(3) = pull
         lines(4) = pull
         lines(5) = groups(i)
         call read_config(write_text('twice.nml', lines), cfg, uerr)
         call check_message(error, uerr, 'twice.nml:5:1: a second &'//known_name(groups(i))// &
            ' group (the first is at line '//achar(iachar('0') + min(i, 3))//'); a file holds one')
         if (allocated(error)) return
      end do
   contains
      pure function known_name(group) result(name)
         character(len=*), intent(in) :: group
         character(len=:), allocatable :: name
         name = group(2:index(group, ' ') - 1)
      end function known_name
   end subroutine test_group_twice

   !> Each test's files are named after it: two tests of one name are an error naming both
   subroutine test_unique_names(error)
      type(error_type), allocatable, intent(out) :: error
      call expect_config_error(error, 'samename.nml', [character(len=90) :: &
         "&test name='a', history='tensile', strain_rate=1e-4, final_strain=0.002 /", &
         "&test name='b', history='tensile', strain_rate=1e-4, final_strain=0.002 /", &
         "&test name='a', history='creep', stress=15.0, ramp_time=1, duration=100 /"], &
         "samename.nml:5: &test #3 'a': name: &test #1 (line 3) has this name")
      if (allocated(error)) return
      ! A name longer than reports hold is refused, not cut in them
      call expect_config_error(error, 'longname.nml', [character(len=260) :: &
         "&test name='"//repeat('n', 129)//"',", "history='tensile', strain_rate=1e-4, final_strain=0.002 /"], &
         "a test name is at most 128 characters")
   end subroutine test_unique_names

   !> Paths and names are never cut: a long one is kept whole, one beyond the limit is refused
   !> naming the variable and the limit
   subroutine test_long_values(error)
      type(error_type), allocatable, intent(out) :: error
      type(run_config) :: cfg
      type(uerror), allocatable :: uerr
      character(len=:), allocatable :: long, too_long, pull
      character(len=5200), allocatable :: lines(:)
      long = repeat('d', 300)
      too_long = repeat('x', 5000)
      pull = "&test name='t', history='tensile', strain_rate=1e-4, final_strain=0.002"
      allocate (lines(4))
      lines(1) = base_model
      lines(2) = base_constants
      lines(3) = "&output out_dir = '"//long//"' /"
      lines(4) = pull//' /'
      call read_config(write_text('long.nml', lines), cfg, uerr)
      if (allocated(uerr)) then
         call test_failed(error, uerr%message)
         return
      end if
      call check(error, cfg%out_dir == scratch_dir//'/'//long, 'a 300-character out_dir is kept whole')
      if (allocated(error)) return
      lines(3) = "&output out_dir = '"//too_long//"' /"
      call read_config(write_text('toolong.nml', lines), cfg, uerr)
      call check_message(error, uerr, 'toolong.nml: &output: out_dir: the value is longer than 4095 characters')
      if (allocated(error)) return
      call expect(pull//", data_file = '"//too_long//"' /", "&test #1 't': data_file: the value is longer than 4095")
      if (allocated(error)) return
      call expect(pull//", backend = 'external', command = '"//too_long//"' /", &
                  "&test #1 't': command: the value is longer than 4095")
      if (allocated(error)) return
      call expect(pull//", filter = 'Cycle 1', '"//repeat('c', 200)//"' /", &
                  "&test #1 't': filter: the value is longer than 128 characters")
   contains
      subroutine expect(test_line, text)
         character(len=*), intent(in) :: test_line, text
         type(run_config) :: c
         character(len=5200) :: deck(3)
         deck(1) = base_model
         deck(2) = base_constants
         deck(3) = test_line
         call read_config(write_text('toolong.nml', deck), c, uerr)
         call check_message(error, uerr, text)
      end subroutine expect
   end subroutine test_long_values

   !> Values no metal test has are a wrong unit, named with the unit expected
   subroutine test_plausible_units(error)
      type(error_type), allocatable, intent(out) :: error
      character(len=*), parameter :: pull = &
         "&test name='a', history='tensile', strain_rate=1e-4, final_strain=0.002 /"
      call expect_model("&model temperature = 20.0, tm = 1800.0, youngs = 22.5e3 /", &
         'temperature = 20.0000 K is below a tenth of tm = 1800.00 K, where no metal is '// &
         'viscoplastic: temperature is in kelvin (K = Celsius + 273.15)')
      if (allocated(error)) return
      call expect_model("&model temperature = 1900.0, tm = 1800.0, youngs = 22.5e3 /", &
         'temperature = 1900.00 K: must lie between 0.1 tm and the melting temperature tm = 1800.00 K')
      if (allocated(error)) return
      call expect_model("&model units = 'MPa', temperature = 1223.15, tm = 1630.0, youngs = 144 /", &
         "youngs = 144.000 MPa is no metal's Young's modulus (1.0E+04 to 7.0E+05 MPa): youngs is"// &
         ' in the model stress unit, MPa (1 GPa = 1000 MPa)')
      if (allocated(error)) return
      call expect_model("&model units = 'ksi', temperature = 1223.15, tm = 1630.0, youngs = 144000 /", &
         "youngs = 144000. ksi is no metal's Young's modulus")
   contains
      subroutine expect_model(model, text)
         character(len=*), intent(in) :: model, text
         type(run_config) :: cfg
         type(uerror), allocatable :: uerr
         character(len=100) :: lines(3)
         lines(1) = model
         lines(2) = base_constants
         lines(3) = pull
         call read_config(write_text('units.nml', lines), cfg, uerr)
         call check_message(error, uerr, 'units.nml: &model: '//text)
      end subroutine expect_model
   end subroutine test_plausible_units

   !> Splitting a file into groups visits each character once: the work of 8000 groups is 8
   !> times that of 1000 (the whole read, 10,000 groups, is timed by bench/input.sh)
   subroutine test_linear_reading(error)
      type(error_type), allocatable, intent(out) :: error
      type(nml_file) :: file
      type(uerror), allocatable :: uerr
      integer :: work(2), ngroups(2), k
      ngroups = [1000, 8000]
      do k = 1, 2
         call scan_namelist_file(write_text('many.nml', many_tests(ngroups(k))), known_groups, &
                                 ['test'], file, uerr)
         if (allocated(uerr)) then
            call test_failed(error, uerr%message)
            return
         end if
         call check(error, size(file%groups), ngroups(k) + 2, 'every group found')
         if (allocated(error)) return
         work(k) = file%work
      end do
      call check(error, real(work(2), dp)/work(1) < 8.1_dp, 'work of 8000 groups / work of 1000 = '// &
                 trim(adjustl(real_text(real(work(2), dp)/work(1)))))
   contains
      function many_tests(n) result(lines)
         integer, intent(in) :: n
         character(len=100), allocatable :: lines(:)
         integer :: i
         character(len=6) :: name
         allocate (lines(n + 2))
         lines(1) = base_model
         lines(2) = base_constants
         do i = 1, n
            write (name, '(a,i5.5)') 't', i
            lines(i + 2) = "&test name='"//name//"', history='tensile', final_strain=0.002 /"
         end do
      end function many_tests
      function real_text(x) result(text)
         real(dp), intent(in) :: x
         character(len=32) :: text
         write (text, '(f0.4)') x
      end function real_text
   end subroutine test_linear_reading

   !> Every variable of every group (taken from the namelist the reader reads, written with its
   !> defaults) has a row in the group's section of docs/reference/namelist.md
   subroutine test_reference_complete(error)
      use usharp_input_model, only: write_model_defaults, write_constants_defaults
      use usharp_model, only: model_type
      use usharp_model_registry, only: model_by_number, n_models
      use usharp_input_solver, only: write_solver_defaults
      use usharp_input_output, only: write_output_defaults
      use usharp_input_fit, only: write_fit_defaults
      use usharp_input_design, only: write_design_defaults
      use usharp_input_diagnose, only: write_diagnose_defaults
      use usharp_input_test, only: write_test_defaults
      type(error_type), allocatable, intent(out) :: error
      character(len=*), parameter :: reference = 'docs/reference/namelist.md'
      character(len=:), allocatable :: doc, missing
      character(len=16), allocatable :: names(:)
      class(model_type), allocatable :: model
      integer :: g, i, unit
      logical :: exists
      inquire (file=reference, exist=exists)
      if (.not. exists) then
         call test_failed(error, reference//' is missing')
         return
      end if
      doc = read_text(reference)
      missing = ''
      do g = 1, size(known_groups)
         open (newunit=unit, file=scratch_dir//'/defaults.nml', status='replace', action='readwrite', &
               delim='apostrophe')
         select case (trim(known_groups(g)))
         case ('model'); call write_model_defaults(unit)
         case ('constants')
            ! Every registered model's constants
            do i = 1, n_models
               call model_by_number(i, model)
               call write_constants_defaults(model, unit)
            end do
         case ('solver'); call write_solver_defaults(unit)
         case ('output'); call write_output_defaults(unit)
         case ('fit'); call write_fit_defaults(unit)
         case ('design'); call write_design_defaults(unit)
         case ('diagnose'); call write_diagnose_defaults(unit)
         case ('test'); call write_test_defaults(unit)
         end select
         rewind (unit)
         call dumped_names(unit, names)
         close (unit, status='delete')
         if (size(names) == 0) then
            missing = missing//' &'//trim(known_groups(g))//' (no variables dumped)'
            cycle
         end if
         do i = 1, size(names)
            if (.not. has_row(section(doc, '## &'//trim(known_groups(g))), names(i))) &
               missing = missing//' &'//trim(known_groups(g))//'%'//trim(names(i))
         end do
      end do
      call check(error, len(missing) == 0, 'not in '//reference//':'//missing)
   contains
      !> Variable names of a namelist dump: lines ' NAME=...' (lower case)
      subroutine dumped_names(unit, names)
         integer, intent(in) :: unit
         character(len=16), allocatable, intent(out) :: names(:)
         character(len=:), allocatable :: line
         character(len=16) :: found(200)
         integer :: e, n
         n = 0
         do
            call read_line(unit, line)
            if (.not. allocated(line)) exit
            e = index(line, '=')
            if (len(line) < 2 .or. e < 3) cycle
            if (line(1:1) /= ' ' .or. verify(line(2:e - 1), 'ABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_') /= 0) cycle
            n = min(n + 1, size(found))
            found(n) = lower_case(line(2:e - 1))
         end do
         names = found(:n)
      end subroutine dumped_names
      subroutine read_line(unit, line)
         integer, intent(in) :: unit
         character(len=:), allocatable, intent(out) :: line
         character(len=1024) :: chunk
         integer :: ios, n
         line = ''
         do
            read (unit, '(a)', advance='no', iostat=ios, size=n) chunk
            if (is_iostat_end(ios)) then
               deallocate (line)
               return
            end if
            line = line//chunk(:n)
            if (ios /= 0) exit   ! end of record
         end do
      end subroutine read_line
      pure function lower_case(text) result(res)
         character(len=*), intent(in) :: text
         character(len=len(text)) :: res
         integer :: i
         res = text
         do i = 1, len(text)
            if (text(i:i) >= 'A' .and. text(i:i) <= 'Z') res(i:i) = achar(iachar(text(i:i)) + 32)
         end do
      end function lower_case
      !> The text of the section headed exactly `heading` (up to the next '## ')
      function section(text, heading) result(part)
         character(len=*), intent(in) :: text, heading
         character(len=:), allocatable :: part
         integer :: a, b
         part = ''
         a = index(new_line('a')//text, new_line('a')//heading//new_line('a'))
         if (a == 0) return
         part = text(a + len(heading):)
         b = index(part, new_line('a')//'## ')
         if (b > 0) part = part(:b)
      end function section
      !> A table row of the variable: a line starting '| `name` |' (case as in the docs)
      logical function has_row(text, name)
         character(len=*), intent(in) :: text, name
         has_row = index(lower_case(new_line('a')//text), new_line('a')//'| `'//trim(name)//'` |') > 0
      end function has_row
   end subroutine test_reference_complete
end module test_input
