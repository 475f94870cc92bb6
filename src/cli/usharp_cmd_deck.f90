!> `usharp deck`: write the APDL input deck of one test (or of every test) of an input file,
!> <out_dir>/<test>.inp, and the constants file the decks read, with the input's constants
module usharp_cmd_deck
   use usharp_error, only: error_type, fatal_error, stat_input
   use usharp_config, only: run_config
   use usharp_input, only: read_config, override_constants
   use usharp_apdl, only: apdl_deck, line_len
   use usharp_external, only: write_constants_file
   use usharp_filesys, only: make_dir, join_path
   use usharp_output, only: write_lines
   implicit none
   private

   public :: deck_command

contains

   !> Write the decks. test_name '' means every test; out_dir '' means &output out_dir.
   subroutine deck_command(path, test_name, out_dir, constants_file, written, error)
      character(len=*), intent(in) :: path, test_name, out_dir, constants_file
      character(len=4096), allocatable, intent(out) :: written(:)
      type(error_type), allocatable, intent(out) :: error
      type(run_config) :: cfg
      character(len=line_len), allocatable :: lines(:)
      character(len=:), allocatable :: dir, command, file
      integer :: i, nmatch
      allocate (written(0))
      call read_config(path, cfg, error)
      if (allocated(error)) return
      command = 'usharp deck'
      if (len(test_name) > 0) command = command//' '//test_name
      command = command//' '//path
      if (len(constants_file) > 0) then
         call override_constants(cfg, constants_file, error)
         if (allocated(error)) return
         command = command//' --constants '//constants_file
      end if
      dir = cfg%out_dir
      if (len(out_dir) > 0) then
         dir = out_dir
         command = command//' --out-dir '//out_dir
      end if
      nmatch = 0
      do i = 1, size(cfg%tests)
         if (len(test_name) > 0 .and. cfg%tests(i)%name /= test_name) cycle
         nmatch = nmatch + 1
      end do
      if (nmatch == 0) then
         call fatal_error(error, path//": no &test named '"//test_name//"'", stat_input)
         return
      end if
      call make_dir(dir, error)
      if (allocated(error)) return
      do i = 1, size(cfg%tests)
         if (len(test_name) > 0 .and. cfg%tests(i)%name /= test_name) cycle
         call apdl_deck(cfg, cfg%tests(i), command, lines, error)
         if (allocated(error)) return
         file = join_path(dir, cfg%tests(i)%name//'.inp')
         call write_lines(file, lines, error)
         if (allocated(error)) return
         written = [character(len=4096) :: written, file]
         ! The constants file the deck reads, from the input's constants
         file = join_path(dir, cfg%tests(i)%ext%constants_file)
         call write_constants_file(file, cfg%model, cfg%tests(i)%ext%constants_format, error)
         if (allocated(error)) return
         if (.not. any(written == file)) written = [character(len=4096) :: written, file]
      end do
   end subroutine deck_command
end module usharp_cmd_deck
