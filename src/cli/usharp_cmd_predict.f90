!> `usharp predict`: the constants of a fit (-c best.nml) applied to tests that were not in
!> it: each test's error figures, the same curves as a fit writes and a summary
module usharp_cmd_predict
   use usharp_kinds, only: dp
   use usharp_error, only: error_type, fatal_error, stat_input, prefix_error
   use usharp_strings, only: real_str, pad, report_line_len
   use usharp_config, only: run_config
   use usharp_input, only: read_config_as, check_inputs_kept, check_not_a_fit
   use usharp_objective, only: fit_problem, setup_problem, simulated
   use usharp_simulation, only: sim_result
   use usharp_output, only: write_lines
   use usharp_filesys, only: make_dir, join_path
   use usharp_cmd_run, only: write_curves, curve_header
   use usharp_overwrite, only: check_overwrite, simulate_mark
   use usharp_experiment, only: data_note
   use usharp_simulate, only: simulate_test
   use usharp_output, only: write_sim_file
   use usharp_config, only: test_config
   implicit none
   private

   public :: predict_command, prediction_errors

contains

   !> Simulate every &test of path with the &constants of constants_file (required) and
   !> compare with the tests' data: RMS error, RMS error / peak of the data, largest error per
   !> test (the fitted response's unit). Writes <test>.sim.txt, <test>.fit.txt and summary.txt
   !> into out_dir (&output out_dir when empty); summary returns the table. A test without a
   !> data_file (a programmed history whose response is wanted) is simulated alone: its
   !> <test>.sim.txt and a row that says so. Files of those names that an earlier prediction
   !> did not write are refused unless force (--force).
   subroutine predict_command(path, out_dir, constants_file, summary, error, force)
      character(len=*), intent(in) :: path, out_dir, constants_file
      character(len=report_line_len), allocatable, intent(out) :: summary(:)
      type(error_type), allocatable, intent(out) :: error
      !> write over files of the output names that usharp predict did not write
      logical, intent(in), optional :: force
      type(run_config) :: cfg
      type(fit_problem) :: prob
      !> the tests without data, simulated alone
      type(test_config), allocatable :: alone(:)
      character(len=512), allocatable :: header(:)
      logical, allocatable :: measured(:)
      type(sim_result), allocatable :: res(:), res_alone(:)
      real(dp) :: rms, rel, worst
      character(len=report_line_len) :: row
      character(len=:), allocatable :: name
      integer :: w
      real(dp), allocatable :: y(:)
      integer, allocatable :: kind(:)
      integer :: i, part
      logical :: overwrite
      allocate (summary(0))
      if (len_trim(constants_file) == 0) then
         call fatal_error(error, 'predict needs the constants of a fit: -c best.nml', stat_input)
         return
      end if
      call read_config_as(path, constants_file, out_dir, cfg, error)
      if (allocated(error)) return
      call check_inputs_kept(cfg, path, constants_file, ['summary.txt'], &
                             [character(len=10) :: '.sim.txt', '.fit.txt', '.peaks.txt'], error)
      if (allocated(error)) return
      ! A fit's folder: its summary and curves have the names of a prediction's
      call check_not_a_fit(cfg, 'predict', ['summary.txt'], &
                           [character(len=10) :: '.sim.txt', '.fit.txt', '.peaks.txt'], error)
      if (allocated(error)) return
      overwrite = .false.
      if (present(force)) overwrite = force
      call check_predict_files(cfg, overwrite, error)
      if (allocated(error)) return
      ! Nothing is fitted; the problem's set-up asks for one fitted constant, unused here
      if (.not. any(cfg%fit%fitted)) cfg%fit%fitted(1) = .true.
      measured = [(cfg%tests(i)%has_data, i=1, size(cfg%tests))]
      alone = pack(cfg%tests, .not. measured)
      cfg%tests = pack(cfg%tests, measured)
      ! The name column as wide as the longest name (with ' peaks'), at least 32
      w = 32
      do i = 1, size(cfg%tests)
         w = max(w, len(cfg%tests(i)%name) + 6)
      end do
      do i = 1, size(alone)
         w = max(w, len(alone(i)%name) + 6)
      end do
      if (size(cfg%tests) > 0) then
         call setup_problem(cfg, prob, error)
         if (allocated(error)) return
         ! Its tests as compared: where the data hold a measurement
         cfg%tests = prob%cfg%tests
      end if
      ! Every simulation before the folder is made: a failing one leaves nothing behind
      allocate (res(size(cfg%tests)), res_alone(size(alone)))
      if (size(cfg%tests) > 0) call prob%simulate_all(cfg%model, res, error)
      if (allocated(error)) return
      do i = 1, size(alone)
         call simulate_test(cfg%model, cfg%solver, alone(i), res_alone(i), error)
         if (allocated(error)) then
            call prefix_error(error, path//': ')
            return
         end if
      end do
      call make_dir(cfg%out_dir, error)
      if (allocated(error)) return
      summary = [character(len=report_line_len) :: 'usharp predict '//path//' with the constants of '// &
         constants_file, '  '//pad('test', w)//'   RMS error    RMS/peak   max error   points']
      do i = 1, size(cfg%tests)
         y = simulated(cfg%tests(i), res(i))
         kind = spread(0, 1, size(y))
         if (cfg%tests(i)%has_peaks()) kind = cfg%tests(i)%point_kind
         ! A test with peaks: one row for its data points, one for its cycles' peaks
         do part = 0, 1
            if (count((kind /= 0) .eqv. (part == 1)) == 0) cycle
            call prediction_errors(pack(prob%targets(i)%y_ex, (kind /= 0) .eqv. (part == 1)), &
                                   pack(y, (kind /= 0) .eqv. (part == 1)), rms, rel, worst)
            name = cfg%tests(i)%name
            if (part == 1) name = cfg%tests(i)%name//' peaks'
            ! (a share too large for f10.2, a prediction far off, in exponent form)
            if (100.0_dp*rel < 1.0e6_dp) then
               write (row, '(es12.4,f10.2,a,es12.4,i9)') rms, 100.0_dp*rel, ' %', worst, &
                  count((kind /= 0) .eqv. (part == 1))
            else
               write (row, '(es12.4,1x,es9.2,a,es12.4,i9)') rms, 100.0_dp*rel, ' %', worst, &
                  count((kind /= 0) .eqv. (part == 1))
            end if
            ! (the note on the test's first row: its peaks' where it compares only those)
            if (part == 0 .or. count(kind == 0) == 0) row = trim(row)//data_note(prob%targets(i)%exp, &
                                                                                 cfg%tests(i)%dt_out)
            summary = [character(len=report_line_len) :: summary, '  '//pad(name, w)//trim(row)]
         end do
      end do
      do i = 1, size(alone)
         summary = [character(len=report_line_len) :: summary, '  '//pad(alone(i)%name, w)// &
                    '   (no data_file: simulated only)']
      end do
      summary = [character(len=report_line_len) :: summary, '  (errors in '//cfg%units// &
         ', strain for stress-controlled tests; peak: the largest |value| of the data; points: '// &
         'those compared)', &
         '  wrote <test>.sim.txt, <test>.fit.txt, summary.txt into '//cfg%out_dir]
      if (any([(cfg%tests(i)%has_peaks(), i=1, size(cfg%tests))])) summary(size(summary)) = &
         trim(summary(size(summary)))//' (and <test>.peaks.txt)'
      if (size(alone) > 0) summary(size(summary)) = trim(summary(size(summary)))// &
         '; only <test>.sim.txt for a test without data'
      if (size(cfg%tests) > 0) then
         call write_curves(prob, cfg%model, cfg%out_dir, constants_file, error, &
                           'prediction with the constants of '//constants_file)
         if (allocated(error)) return
      end if
      do i = 1, size(alone)
         call curve_header(path, constants_file, 'prediction with the constants of '//constants_file, &
                           cfg%model, cfg%units, alone(i), header, error)
         if (allocated(error)) return
         call write_sim_file(join_path(cfg%out_dir, alone(i)%name//'.sim.txt'), res_alone(i), &
                             header, cfg%units, error)
         if (allocated(error)) return
      end do
      call write_lines(join_path(cfg%out_dir, 'summary.txt'), summary, error)
   end subroutine predict_command

   !> A prediction writes over its own earlier files (known by their first lines) and over
   !> the curves of `usharp simulate` (a look at the model, as before a fit); over anything
   !> else only when forced
   subroutine check_predict_files(cfg, force, error)
      type(run_config), intent(in) :: cfg
      logical, intent(in) :: force
      type(error_type), allocatable, intent(out) :: error
      character(len=:), allocatable :: name
      integer :: i
      call check_overwrite(cfg%out_dir, ['summary.txt'], ['usharp predict '], 'predict', force, error)
      do i = 1, size(cfg%tests)
         if (allocated(error)) return
         name = cfg%tests(i)%name
         ! Assigned one by one: gfortran 12 overran the heap building an array constructor of
         ! a length taken from the deferred-length name
         block
            character(len=len(name) + 64) :: marks(3)
            marks(1) = "# usharp * prediction with the constants of *, test '"//name//"'"
            ! (an earlier build's first line, without the program)
            marks(2) = "# prediction with the constants of *, test '"//name//"'"
            marks(3) = simulate_mark//name//"'"
            call check_overwrite(cfg%out_dir, [name//'.sim.txt'], marks, 'predict', force, error)
         end block
         if (allocated(error)) return
         ! (a test without data gets its .sim.txt only)
         if (.not. cfg%tests(i)%has_data) cycle
         call check_overwrite(cfg%out_dir, [name//'.fit.txt'], &
            ["# prediction with the constants of * of test '"//name//"' against "], 'predict', force, error)
         if (allocated(error)) return
         if (cfg%tests(i)%has_peaks()) call check_overwrite(cfg%out_dir, [name//'.peaks.txt'], &
            ["# peak stresses of test '"//name//"' against "], 'predict', force, error)
      end do
   end subroutine check_predict_files

   !> RMS error, RMS error over the peak |measured| and the largest |error| of a prediction
   pure subroutine prediction_errors(y_ex, y_sim, rms, rel, worst)
      real(dp), intent(in) :: y_ex(:), y_sim(:)
      real(dp), intent(out) :: rms, rel, worst
      rms = sqrt(sum((y_ex - y_sim)**2)/real(size(y_ex), dp))
      rel = rms/max(maxval(abs(y_ex)), tiny(1.0_dp))
      worst = maxval(abs(y_ex - y_sim))
   end subroutine prediction_errors
end module usharp_cmd_predict
