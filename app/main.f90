!> usharp command line: argument parsing and dispatch only
program usharp_main
   use, intrinsic :: iso_fortran_env, only: error_unit, output_unit
   use usharp_error, only: error_type, stat_usage
   use usharp_version, only: usharp_version_string
   use usharp_cmd_simulate, only: simulate_command
   implicit none

   character(len=:), allocatable :: command, input, out_dir, arg
   character(len=256), allocatable :: written(:)
   type(error_type), allocatable :: error
   integer :: i, nargs

   nargs = command_argument_count()
   if (nargs == 0) call usage_exit(main_usage())
   command = get_arg(1)
   select case (command)
   case ('-h', '--help')
      write (output_unit, '(a)') main_usage()
      stop
   case ('-V', '--version')
      call print_version()
      stop
   case ('simulate')
      input = ''
      out_dir = ''
      i = 2
      do while (i <= nargs)
         arg = get_arg(i)
         select case (arg)
         case ('-h', '--help')
            write (output_unit, '(a)') simulate_usage()
            stop
         case ('-V', '--version')
            call print_version()
            stop
         case ('-o', '--out-dir')
            i = i + 1
            if (i > nargs) call usage_exit(simulate_usage(), arg//' needs a folder')
            out_dir = get_arg(i)
         case default
            if (arg(1:1) == '-') call usage_exit(simulate_usage(), 'unknown option '//arg)
            if (len(input) > 0) call usage_exit(simulate_usage(), 'more than one input file')
            input = arg
         end select
         i = i + 1
      end do
      if (len(input) == 0) call usage_exit(simulate_usage(), 'no input file given')
      call simulate_command(input, out_dir, written, error)
      if (allocated(error)) call error_exit(error)
      do i = 1, size(written)
         write (output_unit, '(a)') 'wrote '//trim(written(i))
      end do
   case default
      call usage_exit(main_usage(), "unknown command '"//command//"'")
   end select

contains

   function get_arg(k) result(val)
      integer, intent(in) :: k
      character(len=:), allocatable :: val
      integer :: length
      call get_command_argument(k, length=length)
      allocate (character(len=length) :: val)
      if (length > 0) call get_command_argument(k, val)
   end function get_arg

   subroutine print_version()
      write (output_unit, '(a)') 'usharp '//usharp_version_string
   end subroutine print_version

   subroutine usage_exit(text, message)
      character(len=*), intent(in) :: text
      character(len=*), intent(in), optional :: message
      if (present(message)) write (error_unit, '(a)') 'usharp: '//message
      write (error_unit, '(a)') text
      stop stat_usage, quiet=.true.
   end subroutine usage_exit

   subroutine error_exit(err)
      type(error_type), intent(in) :: err
      write (error_unit, '(a)') 'usharp: error: '//err%message
      stop err%stat, quiet=.true.
   end subroutine error_exit

   function main_usage() result(text)
      character(len=:), allocatable :: text
      text = 'usage: usharp <command> [options] <input.nml>'//new_line('a')// &
         new_line('a')//'commands:'//new_line('a')// &
         '  simulate   simulate every &test of the input file, write <out_dir>/<test>.sim.txt'// &
         new_line('a')//new_line('a')//'options:'//new_line('a')// &
         '  -h, --help     show this help (also after a command)'//new_line('a')// &
         '  -V, --version  show the version'//new_line('a')//new_line('a')// &
         'exit codes: 0 success, 1 input error, 2 usage error, 3 failed simulation or fit, '// &
         '4 output not writable'
   end function main_usage

   function simulate_usage() result(text)
      character(len=:), allocatable :: text
      text = 'usage: usharp simulate [options] <input.nml>'//new_line('a')//new_line('a')// &
         'Simulates every &test group of the input file with the &model and &constants'// &
         new_line('a')//'groups and writes one file <out_dir>/<test>.sim.txt per test.'// &
         new_line('a')//new_line('a')//'options:'//new_line('a')// &
         '  -o, --out-dir DIR  write to DIR instead of &output out_dir'//new_line('a')// &
         '  -h, --help         show this help'//new_line('a')// &
         '  -V, --version      show the version'
   end function simulate_usage
end program usharp_main
