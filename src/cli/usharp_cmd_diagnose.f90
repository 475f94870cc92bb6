!> `usharp diagnose`: the diagnosis of a fit (report.md, CSV tables, gnuplot plots in
!> <out_dir>/diagnose) and `usharp diagnose --selfcheck` on synthetic data
module usharp_cmd_diagnose
   use usharp_error, only: error_type
   use usharp_config, only: run_config
   use usharp_input, only: read_config_as, specimen_unused
   use usharp_diagnose, only: diagnose_options, diagnose_result, diagnose_run, write_report, &
                              diagnose_options_of, diagnose_progress, diagnose_journal, &
                              check_diagnosable
   use usharp_diagnose_report, only: report_names, report_marks
   use usharp_overwrite, only: check_overwrite, check_overwrite_each, take_folder
   use usharp_fit, only: fit_fingerprint
   use usharp_objective, only: fit_problem, setup_problem
   use usharp_selfcheck, only: selfcheck_run, selfcheck_report, selfcheck_result, selfcheck_deck
   use usharp_diagnose_specimen, only: specimen_result, specimen_run, specimen_report, specimen_index, &
                                       specimen_csv, specimen_csv_header
   use usharp_diagnose_journal, only: next_unit, record_unit, text_lines, unit_digest
   use usharp_error, only: fatal_error, stat_input, stat_usage
   use usharp_filesys, only: make_dir, join_path, file_exists, unlock_file
   use usharp_output, only: write_lines
   use usharp_mpi, only: is_root, parallel_sync, n_ranks
   use usharp_strings, only: report_line_len
   implicit none
   private

   public :: diagnose_command, selfcheck_command

contains

   !> Diagnose path's tests: the baseline fitted to the fit tests from the deck's constants
   !> or those of constants_file (a best.nml, only a start); progress, when given, is told of
   !> each step (app passes it on a terminal without --quiet). Its optimisations are kept in
   !> <out_dir>/diagnose/diagnose.journal (mode: see run_tasks), so that a diagnosis stopped
   !> by a signal continues with --resume; the per-specimen mode keeps each specimen's report
   !> in <out_dir>/diagnose/specimen.journal alike.
   subroutine diagnose_command(path, out_dir, constants_file, lines, error, progress, mode)
      character(len=*), intent(in) :: path, out_dir, constants_file
      character(len=report_line_len), allocatable, intent(out) :: lines(:)
      type(error_type), allocatable, intent(out) :: error
      procedure(diagnose_progress), optional :: progress
      character(len=*), intent(in), optional :: mode
      type(run_config) :: cfg
      type(diagnose_options) :: opts
      type(diagnose_result) :: res
      type(diagnose_journal) :: journal
      type(error_type), allocatable :: e
      character(len=:), allocatable :: dir, journal_mode
      integer :: lock
      call read_config_as(path, constants_file, out_dir, cfg, error)
      if (allocated(error)) return
      call diagnose_options_of(cfg, opts, error)
      if (allocated(error)) return
      if (len_trim(cfg%diagnose%specimen) > 0) then
         ! (on rank 0 alone under MPI)
         journal_mode = 'start'
         if (present(mode)) journal_mode = mode
         if (is_root()) call specimen_command(cfg, opts, constants_file, lines, error, journal_mode)
         return
      end if
      ! Under MPI every rank runs the diagnosis, the starts of its global stages spread over
      ! them; rank 0 writes the report
      opts%over_ranks = n_ranks() > 1
      ! An input it cannot diagnose leaves no folder or journal behind
      call check_diagnosable(cfg, opts, error)
      if (allocated(error)) return
      dir = join_path(cfg%out_dir, 'diagnose')
      journal_mode = 'start'
      if (present(mode)) journal_mode = mode
      ! A file of the user's among the report's names is refused before any work; the
      ! report of an earlier diagnosis (--resume too) is replaced
      call check_overwrite_each(dir, report_names, report_marks, 'diagnose', journal_mode == 'force', error)
      if (allocated(error)) return
      call check_before_folder(cfg, join_path(dir, 'diagnose.journal'), journal_mode, error)
      if (allocated(error)) return
      ! Held for the diagnosis: a second one into the folder would share its journal
      call take_folder(dir, lock, error)
      if (allocated(error)) return
      ! The journal's own format joins the fingerprint (6: each unit headed by its request's
      ! digest). Units made for other requests (another build of usharp that orders or starts
      ! its runs otherwise) are refused unit by unit as they are replayed (usharp_diagnose_journal)
      call journal%open(join_path(dir, 'diagnose.journal'), fit_fingerprint(cfg, constants_file)// &
                        ' units=6', journal_mode, error)
      if (.not. allocated(error)) then
         call diagnose_run(cfg, opts, res, error, progress=progress, journal=journal)
         call journal%close(e)
         if (allocated(e) .and. .not. allocated(error)) call move_alloc(e, error)
         if (.not. allocated(error) .and. is_root()) call write_report(dir, res, opts, lines, error)
      end if
      call unlock_file(lock)
   end subroutine diagnose_command

   !> Per-specimen mode: each named specimen (or every test) against its replicates;
   !> <out_dir>/diagnose/specimen-<name>.md and its table of effects specimen-<name>.csv.
   !> Each specimen's report and table are a unit of
   !> <out_dir>/diagnose/specimen.journal, so that a run stopped by a signal (a cluster job
   !> at its wall time) continues with --resume from the specimen it had not finished
   subroutine specimen_command(cfg, opts, constants_file, lines, error, mode)
      type(run_config), intent(in) :: cfg
      type(diagnose_options), intent(in) :: opts
      character(len=*), intent(in) :: constants_file
      character(len=report_line_len), allocatable, intent(out) :: lines(:)
      type(error_type), allocatable, intent(out) :: error
      !> what to do with a journal there: 'start', 'resume', 'auto' or 'force'
      character(len=*), intent(in) :: mode
      type(specimen_result) :: sr
      type(diagnose_journal), target :: journal
      type(diagnose_journal), pointer :: jr
      type(error_type), allocatable :: e
      character(len=report_line_len), allocatable :: part(:), verdicts(:)
      character(len=:), allocatable :: report, dir, text, unit_lines(:), table(:), name, unused
      integer, allocatable :: which(:)
      integer :: i, k, at, lock
      character(len=16) :: digest
      logical :: replay
      !> a report's and a table's name and how their first lines begin
      character(len=256) :: own_name(2), own_mark(2)
      if (trim(cfg%diagnose%specimen) == 'all') then
         which = [(i, i=1, size(cfg%tests))]
      else
         which = [specimen_index(cfg, cfg%diagnose%specimen)]
         if (which(1) == 0) then
            call fatal_error(error, cfg%path//": &diagnose: specimen: no &test is named '"// &
               trim(cfg%diagnose%specimen)//"' (name a test, or 'all')", stat_input)
            return
         end if
      end if
      dir = join_path(cfg%out_dir, 'diagnose')
      ! Neither an earlier run's reports (but on --resume, whose journal holds them) nor a
      ! user's file of their names is overwritten unasked (before any work is done)
      do i = 1, size(which)
         name = 'specimen-'//trim(cfg%tests(which(i))%name)
         own_name = [character(len=256) :: name//'.md', name//'.csv']
         own_mark = [character(len=256) :: '# Per-specimen diagnosis: '//trim(cfg%tests(which(i))%name), &
                     specimen_csv_header]
         call check_overwrite_each(dir, own_name, own_mark, 'diagnose', mode == 'force', error)
         if (allocated(error)) return
         do k = 1, size(own_name)
            report = join_path(dir, trim(own_name(k)))
            if (mode == 'start' .and. file_exists(report) .and. &
                .not. file_exists(join_path(dir, 'specimen.journal'))) then
               call fatal_error(error, report//': holds the '//trim(merge('report', 'table ', k == 1))// &
                  ' of an earlier run; start again and overwrite it with --force', stat_usage)
               return
            end if
         end do
      end do
      if (size(cfg%tests) < 2) then
         call fatal_error(error, cfg%path//': &diagnose: specimen: a per-specimen diagnosis needs '// &
            'the specimen and at least one replicate', stat_input)
         return
      end if
      call check_before_folder(cfg, join_path(dir, 'specimen.journal'), mode, error)
      if (allocated(error)) return
      ! Held for the diagnosis (on rank 0 alone: the others do not come here)
      call take_folder(dir, lock, error, alone=.true.)
      if (allocated(error)) return
      ! (units=2: a unit holds the report and then its table)
      call journal%open(join_path(dir, 'specimen.journal'), fit_fingerprint(cfg, constants_file)// &
                        ' specimen='//trim(cfg%diagnose%specimen)//' units=2', mode, error)
      if (allocated(error)) then
         call unlock_file(lock)
         return
      end if
      jr => journal
      allocate (lines(0), verdicts(0))
      do i = 1, size(which)
         digest = unit_digest('specimen '//trim(cfg%tests(which(i))%name))
         call next_unit(jr, digest, text, replay, error)
         if (allocated(error)) exit
         if (replay) then
            ! the report, then the table from its header on
            unit_lines = text_lines(text)
            at = findloc(unit_lines == specimen_csv_header, .true., dim=1)
            if (at == 0) at = size(unit_lines) + 1
            part = unit_lines(:at - 1)
            table = unit_lines(at:)
         else
            call specimen_run(cfg, which(i), opts, .true., sr, error)
            if (allocated(error)) exit
            part = specimen_report(sr)
            table = specimen_csv(sr)
            text = ''
            do k = 1, size(part)
               text = text//trim(part(k))//new_line('a')
            end do
            do k = 1, size(table)
               text = text//trim(table(k))//new_line('a')
            end do
            call record_unit(jr, digest, text, error)
            if (allocated(error)) exit
         end if
         name = join_path(dir, 'specimen-'//trim(cfg%tests(which(i))%name))
         call write_lines(name//'.md', part, error)
         if (allocated(error)) exit
         call write_lines(name//'.csv', table, error)
         if (allocated(error)) exit
         lines = [character(len=report_line_len) :: lines, part, '', 'wrote '//name//'.md, '// &
                  'specimen-'//trim(cfg%tests(which(i))%name)//'.csv', '']
         ! Each specimen's verdict again at the end, side by side
         ! (the whole paragraph: the report wraps it over lines)
         at = findloc(index(part, '**Verdict:** ') == 1, .true., dim=1)
         if (at > 0) then
            verdicts = [character(len=report_line_len) :: verdicts, '- '//trim(part(at)(14:))]
            do k = at + 1, size(part)
               if (len_trim(part(k)) == 0) exit
               verdicts = [character(len=report_line_len) :: verdicts, '  '//trim(part(k))]
            end do
         end if
      end do
      if (size(which) > 1 .and. size(verdicts) > 0 .and. .not. allocated(error)) &
         lines = [character(len=report_line_len) :: lines, '## The verdicts, specimen by specimen', '', verdicts]
      call journal%close(e)
      if (allocated(e) .and. .not. allocated(error)) call move_alloc(e, error)
      call unlock_file(lock)
      ! Settings that do nothing here are said, not passed over
      unused = specimen_unused(cfg%diagnose)
      if (len(unused) > 0 .and. allocated(lines)) lines = [character(len=report_line_len) :: &
         'note: '//cfg%path//': &diagnose: '//unused//': not used by the per-specimen mode (they set '// &
         'the diagnosis of held-out tests and its self-check)', lines]
   end subroutine specimen_command

   !> Self-check of the diagnosis on synthetic data with each effect injected; its
   !> repetitions are kept in <out_dir>/selfcheck.journal (mode: see run_tasks)
   subroutine selfcheck_command(path, out_dir, lines, error, mode)
      character(len=*), intent(in) :: path, out_dir, mode
      character(len=report_line_len), allocatable, intent(out) :: lines(:)
      type(error_type), allocatable, intent(out) :: error
      type(run_config) :: cfg
      type(diagnose_options) :: opts
      type(selfcheck_result) :: sc
      character(len=:), allocatable :: deck, dir
      integer :: lock
      dir = out_dir
      if (len(dir) == 0) dir = 'selfcheck'
      deck = path
      call check_overwrite(dir, ['selfcheck.md'], ['# usharp diagnose --selfcheck'], 'diagnose', &
                           mode == 'force', error)
      if (allocated(error)) return
      ! (the deck is written only when none is given)
      if (len(deck) == 0) call check_overwrite(dir, ['selfcheck.nml'], &
         ['! usharp diagnose --selfcheck'], 'diagnose', mode == 'force', error)
      if (allocated(error)) return
      ! Held for the self-check: a second one into the folder would share its journal
      call take_folder(dir, lock, error)
      if (allocated(error)) return
      call selfcheck_in(deck)
      call unlock_file(lock)
   contains
      !> The self-check in the folder held: the matrix (deck, or the built-in one written)
      subroutine selfcheck_in(deck)
         character(len=:), allocatable, intent(inout) :: deck
         if (len(deck) == 0) then
            ! The built-in matrix, written out so that it can be edited and run again (by rank 0;
            ! the other ranks read it)
            deck = join_path(dir, 'selfcheck.nml')
            if (is_root()) call write_lines(deck, selfcheck_deck(), error)
            call parallel_sync()
            if (allocated(error)) return
         end if
         call read_config_as(deck, '', dir, cfg, error)
         if (allocated(error)) return
         call diagnose_options_of(cfg, opts, error)
         if (allocated(error)) return
         call make_dir(cfg%out_dir, error)
         if (allocated(error)) return
         call selfcheck_run(cfg, opts, sc, error, join_path(cfg%out_dir, 'selfcheck.journal'), mode)
         if (allocated(error)) return
         if (.not. is_root()) return
         lines = selfcheck_report(sc)
         call make_dir(cfg%out_dir, error)
         if (allocated(error)) return
         call write_lines(join_path(cfg%out_dir, 'selfcheck.md'), lines, error)
      end subroutine selfcheck_in
   end subroutine selfcheck_command
   !> What would stop a diagnosis at its start, found before its folder and journal are made:
   !> every test's data read (a held-out test's missing file had left a journal behind; the
   !> data are read again, and the held-out ones used only for the prediction), and --resume
   !> with no journal to resume
   subroutine check_before_folder(cfg, journal_path, mode, error)
      type(run_config), intent(in) :: cfg
      character(len=*), intent(in) :: journal_path, mode
      type(error_type), allocatable, intent(out) :: error
      type(fit_problem) :: prob
      if (mode == 'resume' .and. .not. file_exists(journal_path)) then
         call fatal_error(error, journal_path//': no journal to resume (start without --resume)', &
                          stat_usage)
         return
      end if
      call setup_problem(cfg, prob, error)
   end subroutine check_before_folder
end module usharp_cmd_diagnose
