!> The commands behind one entry point: a parsed command line is executed here and the lines
!> to show the user come back; the program prints them and exits with the error's code.
module usharp_cli
   use usharp_kinds, only: dp
   use usharp_error, only: error_type, stat_report, fatal_error
   use usharp_fit, only: progress_interface
   use usharp_diagnose, only: diagnose_progress
   use usharp_cli_args, only: cli_command, arg_string, parse_arguments, command_names
   use usharp_cli_help, only: main_help, command_help, version_text
   use usharp_cmd_simulate, only: simulate_command
   use usharp_cmd_run, only: run_command
   use usharp_cmd_predict, only: predict_command
   use usharp_cmd_deck, only: deck_command
   use usharp_cmd_identify, only: identify_command
   use usharp_cmd_design, only: design_command
   use usharp_cmd_diagnose, only: diagnose_command, selfcheck_command
   use usharp_mpi, only: is_root, any_rank
   use usharp_signal, only: release_stop_signals, stop_signal, sigterm
   use usharp_strings, only: report_line_len, str
   implicit none
   private

   public :: cli_command, arg_string, parse_arguments, command_names
   public :: main_help, command_help, version_text
   public :: execute_command, progress_interface, diagnose_progress

contains

   !> Execute a parsed command. lines returns what to show on stdout; progress, when given,
   !> is called after every evaluation of a fit, stage at every step of a diagnosis.
   subroutine execute_command(cmd, lines, error, progress, stage)
      !> the parsed command line
      type(cli_command), intent(in) :: cmd
      !> lines for the user (files written, summaries)
      character(len=4200), allocatable, intent(out) :: lines(:)
      !> what went wrong; its stat is the exit code
      type(error_type), allocatable, intent(out) :: error
      !> called with (evaluations, best objective, seconds) during a fit
      procedure(progress_interface), optional :: progress
      !> called with (what it does, simulations, seconds) during a diagnosis
      procedure(diagnose_progress), optional :: stage
      character(len=4096), allocatable :: written(:)
      character(len=report_line_len), allocatable :: summary(:)
      integer :: k, sig

      ! A stop signal since the process began was noted (main catches them first): from here
      ! it ends the process at once, SIGUSR1 (a job script's stop through mpirun or srun) as
      ! SIGTERM does, and one noted before ends the command before it begins. A fit catches
      ! them again and stops cleanly.
      call release_stop_signals()
      if (any_rank(stop_signal() /= 0)) then
         ! (another rank's signal: mpirun passes a stop on to every rank)
         sig = merge(stop_signal(), sigterm, stop_signal() /= 0)
         call fatal_error(error, 'stopped by signal '//str(sig)//' before the command began', 128 + sig)
         allocate (lines(0))
         return
      end if
      ! Under MPI, commands that spread no work over ranks run on rank 0 alone
      if (.not. is_root() .and. .not. (cmd%name == 'run' .or. cmd%name == 'design' .or. &
                                       cmd%name == 'diagnose')) then
         allocate (lines(0))
         return
      end if
      select case (cmd%name)
      case ('simulate', 'deck')
         if (cmd%name == 'simulate') then
            call simulate_command(cmd%input, cmd%out_dir, written, error, cmd%constants, cmd%only_test, &
                                  cmd%force)
         else
            call deck_command(cmd%input, cmd%test_name, cmd%out_dir, cmd%constants, written, error, &
                              cmd%force)
         end if
         if (allocated(error)) return
         allocate (lines(0))
         if (cmd%quiet) return
         lines = [character(len=4200) :: ('wrote '//trim(written(k)), k=1, size(written))]
         return
      case ('predict')
         call predict_command(cmd%input, cmd%out_dir, cmd%constants, summary, error, cmd%force)
      case ('identify')
         call identify_command(cmd%input, cmd%out_dir, cmd%constants, summary, error, cmd%force)
      case ('design')
         call design_command(cmd%input, cmd%out_dir, cmd%constants, summary, error, journal_mode(cmd))
      case ('diagnose')
         if (cmd%selfcheck) then
            call selfcheck_command(cmd%input, cmd%out_dir, summary, error, journal_mode(cmd))
         else
            call diagnose_command(cmd%input, cmd%out_dir, cmd%constants, summary, error, stage, &
                                  journal_mode(cmd))
         end if
      case ('run')
         call run_command(cmd%input, cmd%out_dir, cmd%constants, cmd%resume, summary, error, progress, &
                          cmd%force, cmd%auto_resume)
         ! A fit that is done but whose report failed still shows its summary
         if (allocated(error)) then
            if (error%stat == stat_report) lines = [character(len=4200) :: summary]
         end if
      end select
      if (allocated(error)) return
      ! (the other ranks of an MPI run have nothing to show)
      if (.not. allocated(summary)) allocate (summary(0))
      lines = [character(len=4200) :: summary]
   end subroutine execute_command

   !> How a command with a journal treats one it finds: 'resume', 'auto', 'force' or 'start'
   pure function journal_mode(cmd) result(mode)
      type(cli_command), intent(in) :: cmd
      character(len=:), allocatable :: mode
      mode = 'start'
      if (cmd%force) mode = 'force'
      if (cmd%auto_resume) mode = 'auto'
      if (cmd%resume) mode = 'resume'
   end function journal_mode
end module usharp_cli
