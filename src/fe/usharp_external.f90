!> The external backend: a test simulated by a program of the user's (an FE code in batch mode,
!> as the original ran ANSYS) instead of the internal integrator. Per evaluation usharp makes a
!> work folder of its own, writes the constants file into it, runs the user's command there
!> under a time limit with its output sent to files, checks the exit status and reads the
!> stress history the command wrote. Every failure is an error that says why.
!>
!> The command comes from the namelist only. The placeholders {work}, {constants}, {output}
!> and {input_dir} are replaced by quoted absolute paths, {test} by the test's name (letters,
!> digits, _ - . only). The command is written to usharp-command.sh in the work folder and run
!> there by /bin/sh, started with posix_spawn (no other shell, safe from parallel evaluations)
!> in a process group of its own, stdin from /dev/null, stdout and stderr in the files
!> stdout.txt and stderr.txt there. At the time limit the whole group is stopped.
module usharp_external
   use usharp_kinds, only: dp
   use usharp_error, only: error_type, fatal_error, prefix_error, stat_io, stat_failure
   use usharp_strings, only: str, real_str, shell_quote
   use usharp_model, only: model_type
   use usharp_config, only: external_spec
   use usharp_history, only: history_type, control_strain
   use usharp_prvar, only: read_prvar
   use usharp_table, only: read_columns, merge_repeated_times
   use usharp_units, only: stress_factor
   use usharp_experiment, only: interpolate
   use usharp_output, only: write_lines
   use usharp_process, only: run_process, process_result, proc_exited, proc_timed_out, &
                             proc_stopped, proc_spawn_failed, proc_signalled, &
                             proc_status_lost
   use usharp_signal, only: stop_signal
   use usharp_filesys, only: make_dir, join_path, file_exists, absolute_path, remove_file, &
                             remove_dir
   implicit none
   private

   public :: run_external, write_constants_file, constants_lines, expand_command, n_constants_file
   character(len=*), parameter :: script_name = 'usharp-command.sh'
   character(len=*), parameter :: stdout_name = 'stdout.txt', stderr_name = 'stderr.txt'

contains

   !> Number of values in the constants file: the user material's properties, then the
   !> state variables that start other than zero
   pure integer function n_constants_file(model) result(n)
      class(model_type), intent(in) :: model
      integer, allocatable :: pos(:)
      real(dp), allocatable :: start(:)
      character(len=:), allocatable :: names(:), notes(:)
      call model%fe_start_values(pos, start, names, notes)
      n = model%n_props() + size(pos)
   end function n_constants_file

   !> Write the constants file: the user material's properties (Miller: E, Poisson, A1, A2, B,
   !> C1, C2, k, H1, H2, n, Q, Tm), then the state variables that start other than zero
   !> (Miller: D0); stress in the model unit; one value per line in format fmt
   subroutine write_constants_file(path, model, fmt, error, sync)
      character(len=*), intent(in) :: path, fmt
      class(model_type), intent(in) :: model
      type(error_type), allocatable, intent(out) :: error
      logical, intent(in), optional :: sync  !< see result_commit (default true)
      character(len=64), allocatable :: lines(:)
      call constants_lines(path, model, fmt, lines, error)
      if (.not. allocated(error)) call write_lines(path, lines, error, sync)
   end subroutine write_constants_file

   !> The lines of the constants file path (see write_constants_file): one number each in
   !> fmt; an error where fmt does not fit a number
   subroutine constants_lines(path, model, fmt, lines, error)
      character(len=*), intent(in) :: path, fmt
      class(model_type), intent(in) :: model
      character(len=64), allocatable, intent(out) :: lines(:)
      type(error_type), allocatable, intent(out) :: error
      real(dp) :: vals(n_constants_file(model))
      integer :: ios, k
      character(len=256) :: msg
      integer, allocatable :: pos(:)
      real(dp), allocatable :: start(:)
      character(len=:), allocatable :: names(:), notes(:)
      allocate (lines(size(vals)))
      call model%to_props(vals(:model%n_props()))
      call model%fe_start_values(pos, start, names, notes)
      vals(model%n_props() + 1:) = start
      do k = 1, size(vals)
         write (lines(k), fmt, iostat=ios, iomsg=msg) vals(k)
         if (ios /= 0) then
            call fatal_error(error, path//': constants_format '//fmt//' does not fit a number ('// &
                             trim(msg)//')')
            return
         end if
      end do
   end subroutine constants_lines

   !> The command with its placeholders replaced: {work} {constants} {output} {input_dir} by
   !> quoted paths, {test} by the name
   pure function expand_command(command, work, constants, output, input_dir, test) result(cmd)
      character(len=*), intent(in) :: command, work, constants, output, input_dir, test
      character(len=:), allocatable :: cmd
      integer :: k, j
      character(len=:), allocatable :: key
      cmd = ''
      k = 1
      do while (k <= len(command))
         if (command(k:k) == '{') then
            j = index(command(k:), '}')
            if (j > 0) then
               key = command(k:k + j - 1)
               select case (key)
               case ('{work}'); cmd = cmd//shell_quote(work)
               case ('{constants}'); cmd = cmd//shell_quote(constants)
               case ('{output}'); cmd = cmd//shell_quote(output)
               case ('{input_dir}'); cmd = cmd//shell_quote(input_dir)
               case ('{test}'); cmd = cmd//test
               case default; cmd = cmd//key
               end select
               k = k + j
               cycle
            end if
         end if
         cmd = cmd//command(k:k)
         k = k + 1
      end do
   end function expand_command

   !> Run the external command of a test for a model and return its stress (model unit) at the
   !> output times t_out. The work folders are in out_dir/work; tag makes this one's name
   !> unique (work/<test>.<tag>); input_dir is the namelist's folder. On success the work folder
   !> is removed, on failure it is kept and named in the message.
   subroutine run_external(ext, model, units, hist, test, input_dir, out_dir, tag, t_out, &
                           stress, error)
      type(external_spec), intent(in) :: ext
      class(model_type), intent(in) :: model
      character(len=*), intent(in) :: units, test, input_dir, out_dir, tag
      type(history_type), intent(in) :: hist
      real(dp), intent(in) :: t_out(:)
      real(dp), intent(out) :: stress(:)
      type(error_type), allocatable, intent(out) :: error
      character(len=:), allocatable :: work, cmd, output, constants, in_dir, work_root
      character(len=256) :: names(5)
      character(len=64) :: cols(2)
      real(dp), allocatable :: vals(:, :)
      integer :: nmerged
      character(len=:), allocatable :: script(:)
      type(process_result) :: proc
      character(len=len(script_name) + 2) :: argv(2)
      logical :: gone

      ! gfortran 12 keeps the length of a function's deferred-length character result in a
      ! static variable at each call (join_path's, str's, ...): the threads that run
      ! commands side by side build their paths, files and messages one at a time, and wait
      ! for their commands together
      !$omp critical (usharp_external_text)
      call prepare()
      !$omp end critical (usharp_external_text)
      if (allocated(error)) return
      call run_process(argv, work, stdout_name, stderr_name, ext%time_limit, 5.0_dp, proc)
      !$omp critical (usharp_external_text)
      call finish()
      !$omp end critical (usharp_external_text)

   contains

      !> The work folder, the constants file and the command's script
      subroutine prepare()
         work_root = join_path(out_dir, 'work')
         call make_dir(join_path(work_root, test//'.'//tag), error)
         if (allocated(error)) return
         work = absolute_path(join_path(work_root, test//'.'//tag))
         if (len_trim(input_dir) > 0) then
            in_dir = absolute_path(input_dir)
         else
            in_dir = absolute_path('.')
         end if
         ! Never fall back on the current folder: the constants, script and output would be
         ! written there, and the clean-up would remove files of those names
         if (len(work) == 0) then
            call fatal_error(error, join_path(work_root, test//'.'//tag)//': the work folder vanished '// &
                             'as it was made (cannot resolve its path)')
            return
         end if
         if (len(in_dir) == 0) then
            call fatal_error(error, input_dir//': cannot resolve the input folder''s path')
            return
         end if
         output = join_path(work, ext%output_file)
         constants = join_path(work, ext%constants_file)
         names(1) = ext%output_file
         names(2) = ext%constants_file
         names(3) = script_name
         names(4) = stdout_name
         names(5) = stderr_name
         ! A stale output of an earlier run must never be read as this one's
         gone = remove_file(output)
         if (.not. gone) then
            call fatal_error(error, output//': cannot remove an old output file')
            return
         end if
         call write_constants_file(constants, model, ext%constants_format, error, sync=.false.)
         if (allocated(error)) return
         cmd = expand_command(ext%command, work, constants, output, in_dir, test)
         ! Written whole (renamed into place): the shell never reads half a script
         allocate (character(len=max(len(cmd), 200)) :: script(2))
         script(1) = '# usharp external backend: test '//test//', evaluation '//tag
         script(2) = cmd
         call write_lines(join_path(work, script_name), script, error, sync=.false.)
         if (allocated(error)) return
         ! The script runs in a process group of its own: at the time limit (or when usharp is
         ! asked to stop) the group gets TERM, then KILL 5 s later; what it leaves running is killed
         argv(1) = '/bin/sh'
         argv(2) = './'//script_name
      end subroutine prepare

      !> The command's outcome: its output read into stress, or the error; the folder removed
      !> after a success
      subroutine finish()
         if (proc%how /= proc_exited .or. proc%code /= 0) then
            select case (proc%how)
            case (proc_timed_out)
               call fatal_error(error, 'command ran past its time_limit of '// &
                  real_str(ext%time_limit, 'g0.6')//' s and was stopped')
            case (proc_stopped)
               call fatal_error(error, 'command stopped: usharp received signal '//str(stop_signal()))
            case (proc_spawn_failed)
               call fatal_error(error, 'cannot start /bin/sh (error '//str(proc%code)//')')
            case (proc_status_lost)
               call fatal_error(error, 'the command''s exit status was lost (waitpid failed with '// &
                  'error '//str(proc%code)//'); it was killed')
            case (proc_signalled)
               call fatal_error(error, 'command was killed by signal '//str(proc%code)// &
                  stderr_tail())
            case default
               select case (proc%code)
               case (127)
                  call fatal_error(error, 'command not found (exit status 127): '// &
                     last_line(join_path(work, stderr_name)))
               case (126)
                  call fatal_error(error, 'command not executable (exit status 126): '// &
                     last_line(join_path(work, stderr_name)))
               case default
                  call fatal_error(error, 'command failed with exit status '//str(proc%code)// &
                     stderr_tail())
               end select
            end select
         else if (.not. file_exists(output)) then
            call fatal_error(error, 'command did not write its output file '//ext%output_file)
         else
            ! (element by element: constructors of deferred-length components trip gfortran 12)
            cols(1) = ext%time_title
            cols(2) = ext%stress_title
            if (ext%output_format == 'prvar') then
               call read_prvar(output, cols, vals, error)
            else
               call read_columns(output, cols, vals, error)
            end if
            if (.not. allocated(error)) call to_output_times(vals, error)
         end if
         if (allocated(error)) then
            ! A failing command is a failed simulation, as a failing integrator is (exit 3)
            call prefix_error(error, 'external run (work folder '//work//'): ')
            error%stat = stat_failure
            return
         end if
         call remove_dir(work, names)
      end subroutine finish


      !> ': ' and the last line the command wrote to stderr ('' when it wrote none)
      function stderr_tail() result(text)
         character(len=:), allocatable :: text
         text = last_line(join_path(work, stderr_name))
         if (len(text) > 0) text = ': '//text
      end function stderr_tail

      !> Stress at t_out from the (time, stress) listing: repeated times merged, the unstressed
      !> start added when the listing begins at the first increment, no extrapolation
      subroutine to_output_times(vals, error)
         real(dp), allocatable, intent(inout) :: vals(:, :)
         type(error_type), allocatable, intent(out) :: error
         real(dp) :: start(1, 2)
         if (size(vals, 1) > 0) then
            if (vals(1, 1) > hist%t(1)) then
               start(1, 1) = hist%t(1)
               start(1, 2) = 0.0_dp
               if (hist%control /= control_strain) start(1, 2) = hist%v(1)/ &
                  stress_factor(ext%unit, units)
               vals = reshape([start(1, 1), vals(:, 1), start(1, 2), vals(:, 2)], &
                              [size(vals, 1) + 1, 2])
            end if
         end if
         call merge_repeated_times(vals, output, nmerged, error)
         if (allocated(error)) return
         call interpolate(vals(:, 1), vals(:, 2)*stress_factor(ext%unit, units), t_out, stress, &
                          error)
         if (allocated(error)) call prefix_error(error, output//': short output: ')
      end subroutine to_output_times
   end subroutine run_external

   !> The last non-blank line of a text file, at most 200 characters ('' if none)
   function last_line(path) result(text)
      character(len=*), intent(in) :: path
      character(len=:), allocatable :: text
      character(len=1024) :: line
      integer :: unit, ios
      text = ''
      open (newunit=unit, file=path, status='old', action='read', iostat=ios)
      if (ios /= 0) return
      do
         read (unit, '(a)', iostat=ios) line
         if (ios /= 0) exit
         if (len_trim(line) > 0) text = trim(adjustl(line(:200)))
      end do
      close (unit)
   end function last_line
end module usharp_external
