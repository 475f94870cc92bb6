!> `usharp deck`: write the APDL input deck of one test (or of every test) of an input file,
!> <out_dir>/<test>.inp, and the constants file the decks read, with the input's constants
module usharp_cmd_deck
   use usharp_error, only: error_type, fatal_error, stat_input, stat_usage
   use usharp_config, only: run_config
   use usharp_input, only: read_config, override_constants, check_inputs_kept
   use usharp_apdl, only: apdl_deck, line_len, check_deckable
   use usharp_external, only: constants_lines
   use usharp_simulate, only: test_model
   use usharp_model, only: model_type
   use usharp_filesys, only: make_dir, join_path, file_exists
   use usharp_output, only: write_lines
   use usharp_strings, only: shell_word, str
   use usharp_overwrite, only: check_overwrite, made_by_usharp
   implicit none
   private

   public :: deck_command

contains

   !> Write the decks. test_name '' means every test; out_dir '' means &output out_dir. A file
   !> of a name it writes that an earlier `usharp deck` did not write is refused unless force
   !> (--force).
   subroutine deck_command(path, test_name, out_dir, constants_file, written, error, force)
      character(len=*), intent(in) :: path, test_name, out_dir, constants_file
      character(len=4096), allocatable, intent(out) :: written(:)
      type(error_type), allocatable, intent(out) :: error
      !> write over files of the output names that usharp deck did not write
      logical, intent(in), optional :: force
      type(run_config) :: cfg
      character(len=line_len), allocatable :: lines(:)
      character(len=:), allocatable :: dir, command, file, mark
      character(len=512), allocatable :: consts(:)
      class(model_type), allocatable :: mt
      !> each test's constants file as its lines
      type :: table_lines
         character(len=64), allocatable :: lines(:)
      end type table_lines
      type(table_lines), allocatable :: tables(:)
      integer :: i, j, nmatch
      logical :: overwrite
      overwrite = .false.
      if (present(force)) overwrite = force
      allocate (written(0))
      ! The test's name comes first: given after the input, it would be read as the input
      if (len(test_name) > 0 .and. .not. file_exists(path) .and. file_exists(test_name)) then
         call fatal_error(error, path//': no such input file; usharp deck takes the test''s '// &
            'name first: usharp deck '//shell_word(path)//' '//shell_word(test_name), stat_usage)
         return
      end if
      call read_config(path, cfg, error)
      if (allocated(error)) return
      command = 'usharp deck'
      if (len(test_name) > 0) command = command//' '//shell_word(test_name)
      command = command//' '//shell_word(path)
      if (len(constants_file) > 0) then
         call override_constants(cfg, constants_file, error)
         if (allocated(error)) return
         command = command//' --constants '//shell_word(constants_file)
      end if
      dir = cfg%out_dir
      if (len(out_dir) > 0) then
         dir = out_dir
         command = command//' --out-dir '//shell_word(out_dir)
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
      ! Never over one of its inputs (the deck, the -c file, a test's data), --force or not
      allocate (consts(0))
      do i = 1, size(cfg%tests)
         if (len(test_name) > 0 .and. cfg%tests(i)%name /= test_name) cycle
         consts = [character(len=512) :: consts, cfg%tests(i)%ext%constants_file]
      end do
      cfg%out_dir = dir
      call check_inputs_kept(cfg, path, constants_file, consts, ['.inp'], error, test_name)
      if (allocated(error)) return
      ! The tests that share one constants file read it alike: in one format, with one model
      ! (the drag stress's start D0 follows a test's own temperature)
      allocate (tables(size(cfg%tests)))
      do i = 1, size(cfg%tests)
         if (len(test_name) > 0 .and. cfg%tests(i)%name /= test_name) cycle
         call test_model(cfg%model, cfg%tests(i), mt, error)
         if (.not. allocated(error)) call constants_lines(cfg%tests(i)%ext%constants_file, mt, &
                                                          cfg%tests(i)%ext%constants_format, &
                                                          tables(i)%lines, error)
         if (allocated(error)) return
         do j = 1, i - 1
            if (.not. allocated(tables(j)%lines)) cycle
            if (cfg%tests(j)%ext%constants_file /= cfg%tests(i)%ext%constants_file) cycle
            if (all(tables(j)%lines == tables(i)%lines)) cycle
            call fatal_error(error, path//": &test #"//str(j)//" '"//cfg%tests(j)%name// &
               "' and &test #"//str(i)//" '"//cfg%tests(i)%name//"' read one constants file, "//cfg%tests(i)%ext%constants_file// &
               ', that would hold other numbers for each (another constants_format, or another '// &
               "temperature's D0): give each its own constants_file", stat_input)
            return
         end do
      end do
      ! Every file is checked before the first is written
      do i = 1, size(cfg%tests)
         if (len(test_name) > 0 .and. cfg%tests(i)%name /= test_name) cycle
         call check_deckable(cfg, cfg%tests(i), error)
         if (allocated(error)) return
         mark = deck_mark(cfg%tests(i)%name)
         call check_overwrite(dir, [cfg%tests(i)%name//'.inp'], [mark], 'deck', overwrite, error)
         if (allocated(error)) return
         ! The constants file is numbers alone, with no first line to know it by
         if (.not. read_by_a_deck(cfg, dir, cfg%tests(i)%ext%constants_file)) &
            call check_overwrite(dir, [cfg%tests(i)%ext%constants_file], [character(len=1) ::], &
                                 'deck', overwrite, error)
         if (allocated(error)) return
      end do
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
         call write_lines(file, tables(i)%lines, error)
         if (allocated(error)) return
         if (.not. any(written == file)) written = [character(len=4096) :: written, file]
      end do
   end subroutine deck_command

   !> How the first line of test name's deck begins ('*': the version)
   pure function deck_mark(name) result(mark)
      character(len=*), intent(in) :: name
      character(len=:), allocatable :: mark
      mark = "! usharp * APDL deck for test '"//name//"'"
   end function deck_mark

   !> Whether a deck that usharp wrote in dir, of a test of cfg, reads the constants file
   !> file: then the file is that deck's, written with it
   logical function read_by_a_deck(cfg, dir, file) result(yes)
      type(run_config), intent(in) :: cfg
      character(len=*), intent(in) :: dir, file
      character(len=:), allocatable :: mark
      integer :: j
      yes = .false.
      do j = 1, size(cfg%tests)
         if (cfg%tests(j)%ext%constants_file /= file) cycle
         mark = deck_mark(cfg%tests(j)%name)
         yes = made_by_usharp(join_path(dir, cfg%tests(j)%name//'.inp'), [mark])
         if (yes) return
      end do
   end function read_by_a_deck
end module usharp_cmd_deck
