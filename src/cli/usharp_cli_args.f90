!> The command line parsed into a typed command: which command, its input file and its
!> options. Parsing is pure and reads no global state, so it is tested on argument lists.
module usharp_cli_args
   use usharp_error, only: error_type, fatal_error, stat_usage
   implicit none
   private

   public :: cli_command, arg_string, parse_arguments, command_names, accepts_option

   !> One command-line argument
   type :: arg_string
      character(len=:), allocatable :: s
   end type arg_string

   !> The commands, in the order the help lists them
   character(len=*), parameter :: command_list(*) = [character(len=8) :: &
      'run', 'predict', 'simulate', 'deck', 'identify', 'design', 'diagnose']

   !> A parsed command line
   type :: cli_command
      !> The command (one of command_names()), empty for `usharp --help` / `--version`
      character(len=:), allocatable :: name
      !> The input namelist file (empty only for `diagnose --selfcheck`)
      character(len=:), allocatable :: input
      !> `deck`: the test named before the input file (empty: every test)
      character(len=:), allocatable :: test_name
      !> -o, --out-dir: output folder overriding &output out_dir (empty: none given)
      character(len=:), allocatable :: out_dir
      !> -c, --constants: a namelist file whose &constants replace the input's
      character(len=:), allocatable :: constants
      !> -t, --test: `simulate` only this test
      character(len=:), allocatable :: only_test
      !> --resume: `run`, `design`, `diagnose` (and its --selfcheck) continue a stopped run from its
      !> journal
      logical :: resume = .false.
      !> --force: start again over an earlier run's journal; `predict`, `identify`, `deck`:
      !> write over files of their output names that they did not write
      logical :: force = .false.
      !> --auto-resume: continue from the journal when the output folder holds one, else
      !> start (one command for a job script that may be stopped and started again)
      logical :: auto_resume = .false.
      !> -q, --quiet: no progress line, no list of files written
      logical :: quiet = .false.
      !> --selfcheck: `diagnose` on synthetic data with injected effects
      logical :: selfcheck = .false.
      !> -h, --help was given (after a command: that command's help)
      logical :: help = .false.
      !> -V, --version was given
      logical :: version = .false.
   end type cli_command

contains

   !> The names of the commands
   pure function command_names() result(names)
      character(len=len(command_list)) :: names(size(command_list))
      names = command_list
   end function command_names

   !> Whether a command takes an option (given by its long name, e.g. '--resume')
   pure logical function accepts_option(command, option) result(ok)
      !> the command
      character(len=*), intent(in) :: command
      !> the option's long name
      character(len=*), intent(in) :: option
      select case (option)
      case ('--help', '--version', '--out-dir', '--quiet', '--constants')
         ok = .true.
      case ('--test')
         ok = command == 'simulate'
      case ('--resume', '--auto-resume')
         ok = command == 'run' .or. command == 'design' .or. command == 'diagnose'
      case ('--force')
         ok = command == 'run' .or. command == 'design' .or. command == 'diagnose' .or. &
              command == 'predict' .or. command == 'identify' .or. command == 'deck' .or. &
              command == 'simulate'
      case ('--selfcheck')
         ok = command == 'diagnose'
      case default
         ok = .false.
      end select
   end function accepts_option

   !> Parse the arguments (without the program name) into a command. A usage error (exit
   !> code 2) names the argument; `--help` and `--version` end the parsing.
   pure subroutine parse_arguments(args, cmd, error)
      !> the command-line arguments
      type(arg_string), intent(in) :: args(:)
      !> the parsed command
      type(cli_command), intent(out) :: cmd
      !> usage error
      type(error_type), allocatable, intent(out) :: error
      character(len=:), allocatable :: arg, long
      type(arg_string), allocatable :: positional(:)
      integer :: i, npos
      logical :: ends

      cmd%name = ''
      cmd%input = ''
      cmd%test_name = ''
      cmd%out_dir = ''
      cmd%constants = ''
      cmd%only_test = ''
      if (size(args) == 0) then
         call fatal_error(error, 'no command given', stat_usage)
         return
      end if
      select case (args(1)%s)
      case ('-h', '--help')
         cmd%help = .true.
         return
      case ('help')
         ! usharp help [command]: as usharp --help, usharp <command> --help
         cmd%help = .true.
         if (size(args) >= 2) then
            if (args(2)%s == 'help') return
            if (.not. any(command_list == args(2)%s)) then
               call fatal_error(error, "help: unknown command '"//args(2)%s//"'", stat_usage)
               return
            end if
            cmd%name = args(2)%s
         end if
         return
      case ('-V', '--version')
         cmd%version = .true.
         return
      end select
      if (.not. any(command_list == args(1)%s)) then
         if (index(args(1)%s, '-') == 1) then
            call fatal_error(error, 'unknown option '//args(1)%s, stat_usage)
         else
            call fatal_error(error, "unknown command '"//args(1)%s//"'", stat_usage)
         end if
         return
      end if
      cmd%name = args(1)%s

      npos = 0
      allocate (positional(0))
      i = 2
      ends = .false.
      do while (i <= size(args))
         arg = args(i)%s
         ! After '--' every argument is an input file, a name beginning with '-' among them
         if (ends .or. arg == '--') then
            if (ends) then
               npos = npos + 1
               positional = [positional, arg_string(arg)]
            end if
            ends = .true.
            i = i + 1
            cycle
         end if
         long = long_name(arg)
         if (len(arg) > 0) then
            if (arg(1:1) == '-' .and. len(long) == 0) then
               call fatal_error(error, 'unknown option '//arg, stat_usage)
               return
            end if
         end if
         if (len(long) > 0) then
            if (.not. accepts_option(cmd%name, long)) then
               call fatal_error(error, 'unknown option '//arg, stat_usage)
               return
            end if
         end if
         select case (long)
         case ('--help')
            cmd%help = .true.
            return
         case ('--version')
            cmd%version = .true.
            return
         case ('--out-dir', '--constants', '--test')
            if (i == size(args)) then
               call fatal_error(error, arg//' needs a value', stat_usage)
               return
            end if
            i = i + 1
            ! An empty value (-o '') was passed over, and the deck's own folder used
            if (len_trim(args(i)%s) == 0) then
               call fatal_error(error, arg//" has an empty value ('')", stat_usage)
               return
            end if
            ! A second value would silently replace the first
            if (given(long)) then
               call fatal_error(error, arg//' is given twice', stat_usage)
               return
            end if
            select case (long)
            case ('--out-dir')
               cmd%out_dir = args(i)%s
            case ('--constants')
               cmd%constants = args(i)%s
            case default
               cmd%only_test = args(i)%s
            end select
         case ('--resume')
            cmd%resume = .true.
         case ('--force')
            cmd%force = .true.
         case ('--auto-resume')
            cmd%auto_resume = .true.
         case ('--quiet')
            cmd%quiet = .true.
         case ('--selfcheck')
            cmd%selfcheck = .true.
         case default
            npos = npos + 1
            positional = [positional, arg_string(arg)]
         end select
         i = i + 1
      end do

      if (cmd%resume .and. cmd%force) then
         call fatal_error(error, '--resume continues the journal, --force overwrites it: give one', &
                          stat_usage)
         return
      end if
      if (cmd%auto_resume .and. cmd%force) then
         call fatal_error(error, '--auto-resume continues a journal it finds, --force overwrites it: '// &
                          'give one', stat_usage)
         return
      end if
      ! deck takes an optional test name before the input file; the others one input file
      if (npos > 1 .and. .not. (cmd%name == 'deck' .and. npos == 2)) then
         call fatal_error(error, 'more than one input file', stat_usage)
      else if (npos == 2) then
         cmd%test_name = positional(1)%s
         cmd%input = positional(2)%s
      else if (npos == 1) then
         cmd%input = positional(1)%s
      else if (.not. cmd%selfcheck) then
         call fatal_error(error, 'no input file given', stat_usage)
      end if
      if (.not. allocated(error) .and. cmd%name == 'predict' .and. len(cmd%constants) == 0) &
         call fatal_error(error, 'predict needs the constants of a fit: -c best.nml', stat_usage)
   contains
      !> Whether the option with a value (by its long name) has been given already
      pure logical function given(long)
         character(len=*), intent(in) :: long
         select case (long)
         case ('--out-dir')
            given = len(cmd%out_dir) > 0
         case ('--constants')
            given = len(cmd%constants) > 0
         case default
            given = len(cmd%only_test) > 0
         end select
      end function given
   end subroutine parse_arguments

   !> The long name of an option given in its short or long form; empty when arg is none
   pure function long_name(arg) result(long)
      character(len=*), intent(in) :: arg
      character(len=:), allocatable :: long
      select case (arg)
      case ('-h', '--help')
         long = '--help'
      case ('-V', '--version')
         long = '--version'
      case ('-o', '--out-dir')
         long = '--out-dir'
      case ('-c', '--constants')
         long = '--constants'
      case ('-t', '--test')
         long = '--test'
      case ('-q', '--quiet')
         long = '--quiet'
      case ('--resume', '--selfcheck', '--force', '--auto-resume')
         long = arg
      case default
         long = ''
      end select
   end function long_name
end module usharp_cli_args
