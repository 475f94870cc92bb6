!> `usharp run`: fit the constants to the tests' data with Hooke-Jeeves; write the logs,
!> best.nml, the best fit's curves beside the data, and a summary
module usharp_cmd_run
   use usharp_kinds, only: dp
   use usharp_error, only: error_type, fatal_error, stat_io, stat_report, stat_input, stat_usage
   use usharp_strings, only: str, real_str, pad, shell_word, join, report_line_len
   use usharp_model, only: model_type
   use usharp_config, only: run_config, fit_config, test_config
   use usharp_input, only: read_config_as, check_inputs_kept, output_names
   use usharp_objective, only: fit_problem, setup_problem, simulated
   use usharp_simulate, only: model_lines
   use usharp_experiment, only: fits_strain, response_name, data_note
   use usharp_fit, only: run_fit, fit_outcome, progress_interface
   use usharp_simulation, only: sim_result
   use usharp_output, only: write_sim_file, write_lines, result_file
   use usharp_filesys, only: join_path, unlock_file, file_exists
   use usharp_overwrite, only: made_by_usharp, simulate_mark, check_temporary_names, take_folder
   use usharp_version, only: usharp_version_string
   use usharp_identify, only: identify_result, identify_at, identify_report
   use usharp_mpi, only: is_root, n_ranks, any_rank, share
   use usharp_signal, only: release_stop_signals, stop_signal
   implicit none
   private

   public :: run_command, write_curves, curve_header

   !> The files a run writes in its output folder, and those it writes for each test (after
   !> the test's name)
   character(len=*), parameter :: run_files(9) = [character(len=12) :: 'best.nml', 'summary.txt', &
      'identify.txt', 'GUESS.TXT', 'FOM.TXT', 'SUMS.TXT', 'fit.log', 'fit.journal', 'fit.cache']
   character(len=*), parameter :: test_files(3) = [character(len=10) :: '.sim.txt', '.fit.txt', &
      '.peaks.txt']

contains

   !> Run a fit. out_dir overrides &output out_dir; constants_file, when given, replaces the
   !> starting constants. summary returns the lines to show the user; progress, when given,
   !> is called after every evaluation. force: start again over an earlier run's journal.
   !> The output folder is locked for the run (a second run into it is an error, exit 6).
   !> When the fit finished but its identifiability report failed, the results are written,
   !> the summary says so, and error has stat_report (exit 5).
   subroutine run_command(path, out_dir, constants_file, resume, summary, error, progress, force, &
                          auto_resume)
      character(len=*), intent(in) :: path, out_dir, constants_file
      logical, intent(in) :: resume
      character(len=report_line_len), allocatable, intent(out) :: summary(:)
      type(error_type), allocatable, intent(out) :: error
      procedure(progress_interface), optional :: progress
      logical, intent(in), optional :: force
      !> resume when the output folder holds a journal, else start
      logical, intent(in), optional :: auto_resume
      integer :: lock
      logical :: overwrite

      overwrite = .false.
      if (present(force)) overwrite = force
      lock = -1
      call locked_run()
      ! A stop signal during the writing of the results waited for them to be whole (the fit
      ! itself was done); from here on it ends the process at once again
      call release_stop_signals()
      call unlock_file(lock)

   contains

      subroutine locked_run()
         type(run_config) :: cfg
         type(fit_problem) :: prob
         type(fit_outcome) :: out
         class(model_type), allocatable :: best
         type(identify_result) :: ident
         type(error_type), allocatable :: report_error
         character(len=report_line_len), allocatable :: report(:)
         character(len=:), allocatable :: dir
         real(dp), allocatable :: start(:), dvals(:)
         character(len=:), allocatable :: dnames(:)
         integer :: i, j, w
         logical :: spread
         allocate (summary(0))
         call read_config_as(path, constants_file, out_dir, cfg, error)
         if (allocated(error)) return
         call check_inputs_kept(cfg, path, constants_file, run_files, test_files, error)
         if (allocated(error)) return
         dir = cfg%out_dir
         call check_no_strangers(cfg, dir, resume .or. overwrite, error)
         if (allocated(error)) return
         if (len_trim(constants_file) > 0 .and. cfg%fit%multistart > 0) then
            ! The starts are drawn over the box: constants to start from would not be used
            call fatal_error(error, path//': &fit: multistart = '//str(cfg%fit%multistart)// &
               ' draws its own starts, so -c '//constants_file//' would be ignored; remove '// &
               'multistart to start from those constants, or -c to search from the starts', stat_input)
            return
         end if
         call setup_problem(cfg, prob, error)
         if (allocated(error)) return
         ! Under MPI the other ranks search starts for rank 0, which writes everything, and
         ! compute their share of the identifiability report
         spread = cfg%fit%identify .and. n_ranks() > 1
         ! Rank 0 takes the folder; every rank learns whether it could before any waits for it
         ! in the fit (the others had waited there for ever while rank 0 ended on a locked
         ! or unwritable folder)
         call take_folder(dir, lock, error)
         if (allocated(error)) return
         if (.not. is_root()) then
            call run_fit(prob, dir, resume, out, error, force=overwrite, constants_file=constants_file, &
                         auto_resume=auto_resume)
            if (spread) call identify_over_ranks(prob, out, allocated(error), ident, report_error)
            return
         end if
         call run_fit(prob, dir, resume, out, error, progress, overwrite, constants_file, auto_resume, &
                      hold_signals=.true.)
         if (spread) call identify_over_ranks(prob, out, allocated(error), ident, report_error)
         if (allocated(error)) return

         w = 1
         do j = 1, cfg%model%n_constants()
            w = max(w, len(cfg%model%constant_name(j)))
         end do
         start = [(cfg%model%get_constant(j), j=1, cfg%model%n_constants())]
         call prob%model_of(out%opt%x, best, error)
         if (allocated(error)) return
         call write_best(join_path(dir, 'best.nml'), path, best, cfg%units, out, error)
         if (allocated(error)) return
         call write_curves(prob, best, dir, join_path(dir, 'best.nml'), error)
         if (allocated(error)) return
         ! The fit's results are whole: from here a stop signal ends the process at once (the
         ! report and the summary are written whole or not at all), and one received while
         ! the results were written ends the run now
         call release_stop_signals()
         if (stop_signal() /= 0) then
            call fatal_error(error, 'stopped by signal '//str(stop_signal())//' after the fit was '// &
               'written; its identifiability report and summary.txt were not made (--resume makes them)', &
               128 + stop_signal())
            return
         end if

         summary = [character(len=report_line_len) :: &
            'usharp run '//path//': '//out%opt%reason, &
            '  objective ('//trim(cfg%fit%objective)//'): start '//real_str(out%f_start, 'es12.5')// &
            ', best '//real_str(out%opt%f, 'es12.5'), &
            '  evaluations '//str(out%opt%nevals)//' ('//str(out%nreplayed)//' replayed, '// &
            str(out%nsimulated)//' simulated'//trim(merge(' with the sensitivity Jacobians', &
                                                         '                               ', &
                                                         cfg%fit%jacobian == 'sensitivity'))// &
            '), iterations '// &
            str(out%opt%iterations)//', penalised '//str(out%nfail)//', time '// &
            real_str(out%seconds, 'f10.2')//' s']
         if (size(out%helped) > 1) then
            ! Points simulated whole, and points of which a share of the tests (the rest on
            ! the rank whose search it is)
            summary = [character(len=report_line_len) :: summary, &
               '  ranks '//str(size(out%helped))//'; simulated for another rank''s search: '// &
               join(out%helped, ', ')//' points'//shares_text(out%shared)]
         end if
         do i = 1, size(cfg%tests)
            summary = [character(len=report_line_len) :: summary, '  test '//cfg%tests(i)%name//': '// &
               real_str(out%per_test(i), 'es12.5')//data_note(prob%targets(i)%exp, cfg%tests(i)%dt_out)]
         end do
         summary = [character(len=report_line_len) :: summary, '  constant        start          fitted']
         do j = 1, size(start)
            summary = [character(len=report_line_len) :: summary, '  '//pad(cfg%model%constant_name(j), w)//'  '// &
               real_str(start(j), 'es14.6')//'  '//real_str(best%get_constant(j), 'es14.6')// &
               merge('         ', '  (fixed)', cfg%fit%fitted(j))//start_note(cfg%fit, start(j), j)]
         end do
         call best%derived_values(dnames, dvals)
         do j = 1, size(dvals)
            summary = [character(len=report_line_len) :: summary, '  '//trim(dnames(j))//' = '// &
               real_str(dvals(j), 'g0.6')//' '//cfg%units]
         end do
         summary = [character(len=report_line_len) :: summary, '  wrote '//join_path(dir, 'best.nml')// &
            ', GUESS.TXT, FOM.TXT, SUMS.TXT, fit.log, '// &
            '<test>.fit.txt']
         if (cfg%fit%identify) then
            if (.not. spread) call identify_at(prob, out%constants, cfg%fit%fd_step, ident, report_error)
            if (allocated(report_error)) then
               ! The fit stands: its results are written; the report's failure is a warning
               report = [character(len=report_line_len) :: 'warning: the identifiability report failed: '// &
                         report_error%message]
            else
               report = identify_report(ident)
            end if
            call write_lines(join_path(dir, 'identify.txt'), report, error)
            if (allocated(error)) return
            summary = [character(len=report_line_len) :: summary, report]
         end if
         call write_lines(join_path(dir, 'summary.txt'), summary, error)
         if (allocated(error)) return
         if (allocated(report_error)) call fatal_error(error, 'the fit is done and written, but its '// &
            'identifiability report failed: '//report_error%message, stat_report)
      end subroutine locked_run

      !> A note on constant j's start where a bounded search (all but Hooke-Jeeves) from the
      !> deck's constants began elsewhere: at the bound, the start lying outside its bounds
      pure function start_note(fit, value, j) result(text)
         type(fit_config), intent(in) :: fit
         real(dp), intent(in) :: value
         integer, intent(in) :: j
         character(len=:), allocatable :: text
         text = ''
         if (.not. fit%fitted(j) .or. fit%multistart > 0 .or. fit%method == 'hooke-jeeves') return
         if (value < fit%lower(j)) then
            text = '  (below its lower bound '//real_str(fit%lower(j), 'es10.3')//': searched from it)'
         else if (value > fit%upper(j)) then
            text = '  (above its upper bound '//real_str(fit%upper(j), 'es10.3')//': searched from it)'
         end if
      end function start_note

      !> '; a share of the tests of n1, n2 points' where any rank simulated such shares
      pure function shares_text(shared) result(text)
         integer, intent(in) :: shared(:)
         character(len=:), allocatable :: text
         text = ''
         if (any(shared > 0)) text = '; a share of the tests of '//join(shared, ', ')//' points'
      end function shares_text
   end subroutine run_command

   !> The identifiability report at rank 0's optimum, its Jacobian's points split over the
   !> ranks (every rank calls this after the fit; nothing when the fit failed on any rank)
   subroutine identify_over_ranks(prob, out, failed, ident, report_error)
      type(fit_problem), intent(in) :: prob
      type(fit_outcome), intent(in) :: out    !< the fit's outcome (rank 0's counts)
      logical, intent(in) :: failed           !< the fit ended with an error on this rank
      type(identify_result), intent(out) :: ident
      type(error_type), allocatable, intent(out) :: report_error
      real(dp), allocatable :: c(:)
      if (any_rank(failed)) return
      if (is_root()) c = out%constants
      call share(c, 0)
      call identify_at(prob, c, prob%cfg%fit%fd_step, ident, report_error, spread=.true.)
   end subroutine identify_over_ranks

   subroutine write_best(file, path, best, units, out, error)
      character(len=*), intent(in) :: file, path
      class(model_type), intent(in) :: best
      !> the stress unit of the constants (ksi or MPa)
      character(len=*), intent(in) :: units
      type(fit_outcome), intent(in) :: out
      type(error_type), allocatable, intent(out) :: error
      character(len=report_line_len), allocatable :: lines(:)
      integer :: j
      lines = [character(len=report_line_len) :: &
         '! usharp '//usharp_version_string//' fit of '//path//': objective '// &
         real_str(out%opt%f, 'es12.5')//' after '//str(out%opt%nevals)//' evaluations', &
         '! simulate with it: usharp simulate '//shell_word(path)//' --constants '//shell_word(file)// &
         ' -o '//shell_word(file(:len(file) - len('best.nml'))//'simulated'), &
         ! The model and unit the constants are for: -c checks them against the deck's
         "&model name = '"//best%name()//"', units = '"//units//"' /", '&constants']
      do j = 1, best%n_constants()
         lines = [character(len=report_line_len) :: lines, '  '//lower_name(best%constant_name(j))//' = '// &
            real_str(best%get_constant(j), 'es23.15e3')]
      end do
      lines = [character(len=report_line_len) :: lines, '/']
      call write_lines(file, lines, error)
   contains
      pure function lower_name(name) result(low)
         character(len=*), intent(in) :: name
         character(len=len(name)) :: low
         integer :: k
         low = name
         do k = 1, len(name)
            if (name(k:k) >= 'A' .and. name(k:k) <= 'Z') low(k:k) = achar(iachar(name(k:k)) + 32)
         end do
      end function lower_name
   end subroutine write_best

   !> The best fit's curves: <test>.sim.txt (full response) and <test>.fit.txt (data beside
   !> simulation at the simulation's times, with residual and weight)
   subroutine write_curves(prob, best, dir, constants, error, what)
      type(fit_problem), intent(in) :: prob
      class(model_type), intent(in) :: best
      character(len=*), intent(in) :: dir
      !> the file that holds best's constants (the fit's best.nml, predict's -c)
      character(len=*), intent(in) :: constants
      type(error_type), allocatable, intent(out) :: error
      !> what the constants are, for the files' first lines ('best fit' when absent)
      character(len=*), intent(in), optional :: what
      type(sim_result), allocatable :: res(:)
      integer :: i, k
      type(result_file) :: out
      character(len=160) :: row
      character(len=512), allocatable :: header(:)
      character(len=:), allocatable :: resp, label
      real(dp), allocatable :: y(:)
      allocate (res(size(prob%targets)))
      call prob%simulate_all(best, res, error)
      if (allocated(error)) return
      label = 'best fit'
      if (present(what)) label = what
      do i = 1, size(prob%targets)
         call curve_header(prob%cfg%path, constants, label, best, prob%cfg%units, prob%cfg%tests(i), &
                           header, error)
         if (allocated(error)) return
         call write_sim_file(join_path(dir, prob%cfg%tests(i)%name//'.sim.txt'), once_a_time(res(i)), &
                             header, prob%cfg%units, error)
         if (allocated(error)) return
         call out%open(join_path(dir, prob%cfg%tests(i)%name//'.fit.txt'), error)
         if (allocated(error)) return
         call out%line('# '//label//" of test '"//prob%cfg%tests(i)%name//"' against "//prob%cfg%tests(i)%data%file)
         resp = response_name(prob%cfg%tests(i), prob%cfg%units)
         call out%line('# columns: time (s), strain (-), measured '//resp//', simulated '// &
            resp//', residual, weight (-); stress ('//prob%cfg%units//') of the simulation')
         call out%line('# time strain '//merge('strain_exp', 'stress_exp', fits_strain(prob%cfg%tests(i)))// &
            ' '//merge('strain_sim', 'stress_sim', fits_strain(prob%cfg%tests(i)))//' residual weight stress')
         y = simulated(prob%cfg%tests(i), res(i))
         do k = 1, size(prob%targets(i)%t)
            write (row, '(7es20.11e3)') prob%targets(i)%t(k), res(i)%strain(k), prob%targets(i)%y_ex(k), &
               y(k), prob%targets(i)%y_ex(k) - y(k), prob%targets(i)%w(k), res(i)%stress(k)
            call out%line(row)
         end do
         call out%commit(error)
         if (allocated(error)) return
         if (prob%cfg%tests(i)%has_peaks()) then
            call write_peaks(join_path(dir, prob%cfg%tests(i)%name//'.peaks.txt'), prob, i, &
                             res(i), error)
            if (allocated(error)) return
         end if
      end do
   end subroutine write_curves

   !> A response with each time once: a turning point compared both as a data point and as a
   !> peak (target 'both') is one row of the curve, not two
   pure function once_a_time(r) result(o)
      type(sim_result), intent(in) :: r
      type(sim_result) :: o
      logical, allocatable :: keep(:)
      integer :: n
      n = size(r%t)
      allocate (keep(n))
      keep = .true.
      if (n > 1) keep(2:) = r%t(2:) /= r%t(:n - 1)
      o = r
      o%t = pack(r%t, keep)
      o%strain = pack(r%strain, keep)
      o%stress = pack(r%stress, keep)
      o%eps_in = pack(r%eps_in, keep)
      o%back = pack(r%back, keep)
      o%drag = pack(r%drag, keep)
   end function once_a_time

   !> The first lines of a <test>.sim.txt of the constants in the file constants (what they
   !> are: label): the program, the `usharp simulate` command of the same curve, the model
   subroutine curve_header(path, constants, label, model, units, test, header, error)
      character(len=*), intent(in) :: path, constants, label, units
      class(model_type), intent(in) :: model
      type(test_config), intent(in) :: test
      character(len=512), allocatable, intent(out) :: header(:)
      type(error_type), allocatable, intent(out) :: error
      ! (simulate writes every output time; a fit's curve those compared with the data)
      header = [character(len=512) :: 'usharp '//usharp_version_string//' '//label//", test '"// &
                test%name//"'", 'the same curve, at every output time: usharp simulate '//shell_word(path)// &
                ' --constants '//shell_word(constants)//' --test '//shell_word(test%name)]
      header = [character(len=512) :: header, model_lines(model, units, test, error)]
   end subroutine curve_header

   !> <test>.peaks.txt: each compared peak stress of test i beside the simulated stress at its
   !> turning point, with the simulated cycle's number (the cyclic hardening or softening curve)
   subroutine write_peaks(file, prob, i, res, error)
      character(len=*), intent(in) :: file
      type(fit_problem), intent(in) :: prob
      integer, intent(in) :: i
      type(sim_result), intent(in) :: res
      type(error_type), allocatable, intent(out) :: error
      type(result_file) :: out
      character(len=160) :: row
      integer :: k
      associate (test => prob%cfg%tests(i), tg => prob%targets(i))
         call out%open(file, error)
         if (allocated(error)) return
         call out%line("# peak stresses of test '"//test%name//"' against "//test%peak_file)
         call out%line('# columns: cycle, +1 maximum or -1 minimum, time (s), strain (-), '// &
                       'measured and simulated stress ('//prob%cfg%units//')')
         call out%line('# cycle kind time strain stress_exp stress_sim')
         do k = 1, size(tg%t)
            if (test%point_kind(k) == 0) cycle
            write (row, '(i8,i4,4es20.11e3)') test%peak_cycle(k), test%point_kind(k), tg%t(k), &
               res%strain(k), tg%y_ex(k), res%stress(k)
            call out%line(row)
         end do
         call out%commit(error)
      end associate
   end subroutine write_peaks

   !> A run starts in a folder only where it overwrites nothing a user made: files of the
   !> names it writes or of their temporary names (<name>.part), with no journal that says a
   !> run made them (a journal's own case, an earlier run, is run_fit's), are refused unless
   !> allowed (--force, or --resume)
   subroutine check_no_strangers(cfg, dir, allowed, error)
      type(run_config), intent(in) :: cfg
      character(len=*), intent(in) :: dir
      logical, intent(in) :: allowed
      type(error_type), allocatable, intent(out) :: error
      character(len=:), allocatable :: names(:)
      integer :: i
      ! (--auto-resume without a journal starts afresh, as a plain run does)
      if (allowed .or. file_exists(join_path(dir, 'fit.journal'))) return
      names = output_names(cfg, run_files, test_files)
      call check_temporary_names(dir, names, 'run', error)
      if (allocated(error)) return
      do i = 1, size(names)
         if (simulated_by_usharp(join_path(dir, trim(names(i))))) cycle
         if (file_exists(join_path(dir, trim(names(i))))) then
            call fatal_error(error, join_path(dir, trim(names(i)))//': a file of this name '// &
               'is there, and no fit.journal says a run made it; overwrite it with --force, '// &
               'or give another output folder (-o)', stat_usage)
            return
         end if
      end do
   end subroutine check_no_strangers

   !> Whether path is a test's curve that `usharp simulate` wrote (its first line says so): a
   !> look at the model before the fit, into the folder the fit then writes (the user guide's
   !> workflow), not a file of the user's
   logical function simulated_by_usharp(path) result(yes)
      character(len=*), intent(in) :: path
      yes = .false.
      if (index(path, '.sim.txt', back=.true.) /= len(path) - len('.sim.txt') + 1) return
      yes = made_by_usharp(path, [simulate_mark])
   end function simulated_by_usharp

end module usharp_cmd_run
