!> usharp command line: parse the arguments into a command, execute it, print, exit
program usharp_main
   use, intrinsic :: iso_c_binding, only: c_int
   use, intrinsic :: iso_fortran_env, only: error_unit
   use usharp_kinds, only: dp
   use usharp_error, only: error_type, stat_usage, stat_input
   use usharp_filesys, only: raw_file, standard_output
   use usharp_strings, only: str, real_str
   use usharp_cli, only: cli_command, arg_string, parse_arguments, execute_command, &
                         main_help, command_help, version_text
   use usharp_cli_threads, only: ensure_wait_policy
   use usharp_mpi, only: parallel_start, parallel_stop, is_root, this_rank
   use usharp_signal, only: catch_stop_signals
   implicit none
   type(arg_string), allocatable :: args(:)
   type(cli_command) :: cmd
   type(error_type), allocatable :: error
   character(len=4200), allocatable :: lines(:)
   integer :: i, length
   !> a write to standard output failed (a full disk, a closed pipe): the results a script
   !> reads there are not whole, which the exit status says (exit 4)
   type(error_type), allocatable :: out_error

   interface
      function c_isatty(fd) bind(C, name='isatty') result(r)
         import :: c_int
         integer(c_int), value :: fd
         integer(c_int) :: r
      end function c_isatty
   end interface

   call ensure_wait_policy()
   ! A stop signal (SIGTERM, SIGINT, a job script's SIGUSR1) is noted from here on, through
   ! the launch of MPI, and ends the command as it begins (see execute_command)
   call catch_stop_signals()
   ! Under an MPI launcher every rank runs the command; rank 0 alone prints
   call parallel_start()
   allocate (args(command_argument_count()))
   do i = 1, size(args)
      call get_command_argument(i, length=length)
      allocate (character(len=length) :: args(i)%s)
      if (length > 0) call get_command_argument(i, args(i)%s)
   end do
   call parse_arguments(args, cmd, error)
   ! A usage error is one line, with where the usage is
   if (allocated(error) .and. is_root()) then
      if (len(cmd%name) > 0) then
         write (error_unit, '(a)') 'usharp: error: '//error%message//' (usharp '//cmd%name// &
            ' --help for its usage)'
      else
         write (error_unit, '(a)') 'usharp: error: '//error%message//' (usharp --help for the commands)'
      end if
   end if
   if (allocated(error)) call finish(stat_usage)
   if (cmd%version .and. is_root()) call put(version_text())
   if (cmd%help .and. is_root()) then
      if (len(cmd%name) > 0) then
         call put(command_help(cmd%name))
      else
         call put(main_help())
      end if
   end if
   if (cmd%version .or. cmd%help) call finish(0)

   ! The progress line goes to stderr only on a terminal and without --quiet
   if (.not. cmd%quiet .and. c_isatty(2_c_int) == 1 .and. is_root()) then
      call execute_command(cmd, lines, error, show_progress, show_stage)
      if (cmd%name == 'run' .or. cmd%name == 'diagnose') write (error_unit, '(a)') ''
   else
      call execute_command(cmd, lines, error)
   end if
   ! (lines come with an error only where the results stand: a fit whose report failed)
   if (allocated(lines) .and. is_root()) then
      do i = 1, size(lines)
         call put(trim(lines(i)))
      end do
   end if
   if (allocated(error)) then
      if (is_root()) then
         write (error_unit, '(a)') 'usharp: error: '//error%message
      else if (error%stat /= stat_input .and. error%stat /= stat_usage .and. error%stat < 128) then
         ! Errors of the input every rank finds alike; rank 0 has said them
         write (error_unit, '(a)') 'usharp: rank '//str(this_rank())//': error: '//error%message
      end if
      call finish(error%stat)
   end if
   call finish(0)

contains

   !> Stop MPI (when running under it) and exit with code; with code 0, exit 4 when what was
   !> written to standard output did not reach it
   subroutine finish(code)
      integer, intent(in) :: code
      integer :: exit_code
      exit_code = code
      if (allocated(out_error) .and. exit_code == 0) then
         write (error_unit, '(a)') 'usharp: error: '//out_error%message
         exit_code = out_error%stat
      end if
      call parallel_stop()
      ! quiet: no note of floating-point flags on stderr, which a model's trial points raise
      stop exit_code, quiet=.true.
   end subroutine finish

   !> One line to standard output; the first failure is kept (see finish) and ends the writing
   subroutine put(text)
      character(len=*), intent(in) :: text
      type(raw_file) :: out
      if (allocated(out_error)) return
      out = standard_output()
      call out%put(text//new_line('a'), out_error)
   end subroutine put

   subroutine show_progress(nevals, best, seconds)
      integer, intent(in) :: nevals
      real(dp), intent(in) :: best, seconds
      write (error_unit, '(a)', advance='no') achar(13)//'usharp run: '//str(nevals)// &
         ' evaluations, best '//real_str(best, 'es11.4')//', '//real_str(seconds, 'f10.1')//' s   '
      flush (error_unit)
   end subroutine show_progress

   subroutine show_stage(stage, nevals, seconds)
      character(len=*), intent(in) :: stage
      integer, intent(in) :: nevals
      real(dp), intent(in) :: seconds
      write (error_unit, '(a)', advance='no') achar(13)//'usharp diagnose: '//stage//', '// &
         str(nevals)//' simulations, '//real_str(seconds, 'f10.1')//' s'//achar(27)//'[K'
      flush (error_unit)
   end subroutine show_stage
end program usharp_main
