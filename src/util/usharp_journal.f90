!> The journal of a long computation made of units done in a fixed order (the tasks of a task
!> farm, the optimisations of a diagnosis): each unit's result as text, so that a stopped run
!> continues (--resume) from the units done. Every rank reads it, rank 0 alone writes.
!>
!> The file: a fingerprint line (the input, data files included), then per unit a line
!> `task <k> <n>`, the n lines of its result and a line `end <k>`; a block cut short by a
!> kill is dropped when it is read, and the units are numbered 1, 2, ... without a gap.
module usharp_journal
   use, intrinsic :: iso_fortran_env, only: int64
   use usharp_error, only: error_type, fatal_error, stat_input, stat_usage
   use usharp_strings, only: str
   use usharp_filesys, only: raw_file, file_exists, read_line
   use usharp_mpi, only: is_root, any_rank, parallel_sync
   implicit none
   private

   public :: task_text, journal_file, fingerprint_mismatch, fingerprint_damaged

   !> One unit's result
   type :: task_text
      character(len=:), allocatable :: s
   end type task_text

   !> An open journal: the units read back from it (done) and the file rank 0 appends to
   type :: journal_file
      !> The results found on opening it, in order (none when started anew)
      type(task_text), allocatable :: done(:)
      character(len=:), allocatable :: path
      type(raw_file), private :: out
      logical, private :: is_open = .false.
   contains
      procedure :: open => journal_open
      procedure :: put => journal_put
      procedure :: close => journal_close
   end type journal_file

   character(len=*), parameter :: fingerprint_tag = '# fingerprint '

contains

   !> Open the journal at path for a run whose input has this fingerprint. mode: 'start' (a
   !> journal with results is an error), 'force' (start again over it), 'resume' (continue
   !> it; it must exist and have the same fingerprint) or 'auto' (resume when it holds
   !> results, else start). Collective over the ranks. most: the units the run has at most.
   subroutine journal_open(self, path, fingerprint, mode, error, most)
      class(journal_file), intent(inout) :: self
      character(len=*), intent(in) :: path, fingerprint, mode
      type(error_type), allocatable, intent(out) :: error
      integer, intent(in), optional :: most
      character(len=:), allocatable :: old_fingerprint
      logical :: resuming
      integer :: k
      self%path = path
      ! (a journal object may be opened again after its close)
      if (allocated(self%done)) deallocate (self%done)
      allocate (self%done(0))
      resuming = mode == 'resume'
      if (mode == 'auto') resuming = has_results(path)
      if (resuming) then
         call read_journal(path, self%done, old_fingerprint, error)
         if (.not. allocated(error)) then
            if (fingerprint_damaged(path, old_fingerprint, fingerprint)) call fatal_error(error, &
               path//': cannot resume: the journal is damaged (its fingerprint line is cut '// &
               'short); start again with --force', stat_input)
         end if
         if (.not. allocated(error) .and. old_fingerprint /= fingerprint) &
            call fatal_error(error, path//': cannot resume: '//changed_part(old_fingerprint, fingerprint)// &
               ' changed since the journal was written (start again with --force)', stat_input)
         if (.not. allocated(error) .and. present(most)) then
            if (size(self%done) > most) call fatal_error(error, path//': cannot resume: it '// &
               'holds more tasks than this run has', stat_input)
         end if
         if (allocated(error)) return
      else if (mode /= 'force' .and. has_results(path)) then
         call fatal_error(error, path//': holds the journal of an earlier run; continue it '// &
            'with --resume, or start again and overwrite it with --force', stat_usage)
         return
      end if
      ! Every rank has read the journal before rank 0 writes it again
      call parallel_sync()
      if (is_root()) then
         call self%out%create(path, error)
         if (.not. allocated(error)) call self%out%put(fingerprint_tag//fingerprint//new_line('a'), error)
         do k = 1, size(self%done)
            if (.not. allocated(error)) call self%out%put(block(k, self%done(k)%s), error)
         end do
      end if
      self%is_open = .true.
      if (any_rank(allocated(error))) then
         if (.not. allocated(error)) call fatal_error(error, path//': rank 0 cannot write it')
         call self%close()
      end if
   end subroutine journal_open

   !> Unit k's result (lines each ended by new_line('a')) appended, by rank 0
   subroutine journal_put(self, k, text, error)
      class(journal_file), intent(inout) :: self
      integer, intent(in) :: k
      character(len=*), intent(in) :: text
      type(error_type), allocatable, intent(out) :: error
      if (self%is_open .and. is_root()) call self%out%put(block(k, text), error)
   end subroutine journal_put

   !> Close the journal (rank 0's file); error: the close failed
   subroutine journal_close(self, error)
      class(journal_file), intent(inout) :: self
      type(error_type), allocatable, intent(out), optional :: error
      type(error_type), allocatable :: e
      if (.not. self%is_open) return
      self%is_open = .false.
      if (.not. is_root()) return
      call self%out%close(e)
      if (present(error) .and. allocated(e)) call move_alloc(e, error)
   end subroutine journal_close

   !> Unit k's block in the journal
   pure function block(k, text) result(b)
      integer, intent(in) :: k
      character(len=*), intent(in) :: text
      character(len=:), allocatable :: b
      b = 'task '//str(k)//' '//str(count_lines(text))//new_line('a')//text//'end '//str(k)// &
          new_line('a')
   end function block

   pure integer function count_lines(text) result(n)
      character(len=*), intent(in) :: text
      integer :: i
      n = 0
      do i = 1, len(text)
         if (text(i:i) == new_line('a')) n = n + 1
      end do
   end function count_lines

   !> Whether a journal holds a result
   logical function has_results(path)
      character(len=*), intent(in) :: path
      type(task_text), allocatable :: done(:)
      character(len=:), allocatable :: fp
      type(error_type), allocatable :: error
      has_results = .false.
      if (.not. file_exists(path)) return
      call read_journal(path, done, fp, error)
      has_results = .not. allocated(error) .and. size(done) > 0
   end function has_results

   !> The fingerprint and the whole results, in order, of a journal
   subroutine read_journal(path, done, fingerprint, error)
      character(len=*), intent(in) :: path
      type(task_text), allocatable, intent(out) :: done(:)
      character(len=:), allocatable, intent(out) :: fingerprint
      type(error_type), allocatable, intent(out) :: error
      character(len=:), allocatable :: line, text
      integer :: unit, ios, k, n, j
      character(len=8) :: word
      allocate (done(0))
      fingerprint = ''
      if (.not. file_exists(path)) then
         call fatal_error(error, path//': no journal to resume from (start without --resume)', stat_input)
         return
      end if
      open (newunit=unit, file=path, status='old', action='read', iostat=ios)
      if (ios /= 0) then
         call fatal_error(error, path//': cannot read it', stat_input)
         return
      end if
      do
         call read_line(unit, line, ios)
         if (ios /= 0) exit
         if (index(line, fingerprint_tag) == 1) then
            fingerprint = line(len(fingerprint_tag) + 1:)
            cycle
         end if
         read (line, *, iostat=ios) word, k, n
         if (ios /= 0 .or. word /= 'task' .or. k /= size(done) + 1) exit
         text = ''
         do j = 1, n
            call read_line(unit, line, ios)
            if (ios /= 0) exit
            text = text//line//new_line('a')
         end do
         ! A block cut short by a kill is not a result
         if (ios /= 0) exit
         call read_line(unit, line, ios)
         if (ios /= 0 .or. line /= 'end '//str(k)) exit
         done = [done, task_text(text)]
      end do
      close (unit)
   end subroutine read_journal


   !> What fingerprint_mismatch names, or 'the input' when it names nothing
   function changed_part(old, new) result(what)
      character(len=*), intent(in) :: old, new
      character(len=:), allocatable :: what
      what = fingerprint_mismatch(old, new)
      if (len(what) == 0) what = 'the input'
   end function changed_part

   !> Whether the fingerprint old, read from the first line of the journal at path, was cut
   !> short (a damaged file, not a changed input): its line has no end (the file ends within
   !> it, its last items missing), or an item is cut within its name or value (a file's hash
   !> is 16 hex digits). Told apart from a change, which fingerprint_mismatch names as such;
   !> a whole line of fewer items is another layout's (an earlier version's)
   logical function fingerprint_damaged(path, old, new) result(damaged)
      !> the journal
      character(len=*), intent(in) :: path
      !> its fingerprint (without the tag) and the run's
      character(len=*), intent(in) :: old, new
      integer(int64) :: bytes
      integer :: k, nold
      damaged = .true.
      inquire (file=path, size=bytes)
      if (bytes >= 0 .and. bytes <= len(fingerprint_tag) + len(old)) return
      nold = count_items(old)
      do k = 1, nold
         if (.not. whole(item(old, k))) return
         ! (a name cut short: the run's item there has a value)
         if (index(item(old, k), '=') == 0 .and. index(item(new, k), '=') > 0) return
      end do
      damaged = .false.
   contains
      !> How many items a fingerprint has (separated by blanks)
      pure integer function count_items(list) result(n)
         character(len=*), intent(in) :: list
         n = 0
         do while (len(item(list, n + 1)) > 0)
            n = n + 1
         end do
      end function count_items
      !> The k-th item of a fingerprint ('' past its end)
      pure function item(list, k) result(text)
         character(len=*), intent(in) :: list
         integer, intent(in) :: k
         character(len=:), allocatable :: text
         integer :: pos, next, n
         text = ''
         pos = 1
         n = 0
         do while (pos <= len_trim(list))
            next = index(list(pos:)//' ', ' ') + pos - 1
            if (next > pos) then
               n = n + 1
               if (n == k) then
                  text = list(pos:next - 1)
                  return
               end if
            end if
            pos = next + 1
         end do
      end function item
      pure function name_of(text) result(name)
         character(len=*), intent(in) :: text
         character(len=:), allocatable :: name
         name = text(:max(0, index(text, '=') - 1))
      end function name_of
      !> No '=', or a name and a value; a file's hash of 16 hex digits (or 'unreadable')
      pure logical function whole(text)
         character(len=*), intent(in) :: text
         character(len=:), allocatable :: name, val
         integer :: eq
         eq = index(text, '=')
         whole = eq == 0
         if (eq == 0) return
         if (eq == 1) return
         name = text(:eq - 1)
         val = text(eq + 1:)
         if (len(val) == 0) return
         if (name == 'input' .or. name == 'constants' .or. index(name, 'data:') == 1 .or. &
             index(name, 'history:') == 1 .or. index(name, 'peaks:') == 1) then
            whole = val == 'unreadable' .or. (len(val) == 16 .and. verify(val, '0123456789ABCDEF') == 0)
         else
            whole = .true.
         end if
      end function whole
   end function fingerprint_damaged

   !> '' when the fingerprints agree, else what changed (the fingerprint is a list of
   !> name=value items; see usharp_fit). old must not be empty.
   function fingerprint_mismatch(old, new) result(what)
      character(len=*), intent(in) :: old, new
      character(len=:), allocatable :: what
      character(len=:), allocatable :: item, name, old_value
      integer :: pos, next, eq
      what = ''
      call compare(new, old, .false.)
      ! An item the journal has and this run lacks (a file given then, such as -c, and not
      ! now) is a change too
      call compare(old, new, .true.)
   contains
      !> Each item of list whose value differs in other (or, absent_only, that other lacks)
      subroutine compare(list, other, absent_only)
         character(len=*), intent(in) :: list, other
         logical, intent(in) :: absent_only
         pos = 1
         do while (pos <= len_trim(list))
            next = index(list(pos:), ' ')
            if (next == 0) then
               item = list(pos:len_trim(list))
               next = len_trim(list) + 1
            else
               item = list(pos:pos + next - 2)
               next = pos + next
            end if
            pos = next
            if (len(item) == 0) cycle
            eq = index(item, '=')
            if (eq < 2) cycle
            name = item(:eq - 1)
            old_value = value_of(other, name)
            if (absent_only) then
               if (old_value /= '(none)') cycle
               if (len(what) > 0) what = what//', '
               what = what//describe(name)
               ! The one file a run may be given or not (-c): say which way it changed
               if (name == 'constants') what = what//', given then and not now,'
            else if (old_value /= item(eq + 1:)) then
               if (len(what) > 0) what = what//', '
               what = what//describe(name)
               if (name == 'constants' .and. old_value == '(none)') what = what//', not given then,'
            end if
         end do
      end subroutine compare
      function value_of(list, name) result(val)
         character(len=*), intent(in) :: list, name
         character(len=:), allocatable :: val
         integer :: at, stop_at
         val = '(none)'
         at = index(' '//list//' ', ' '//name//'=')
         if (at == 0) return
         stop_at = index(list(at:)//' ', ' ')
         val = list(at + len(name) + 1:at + stop_at - 2)
      end function value_of
      function describe(name) result(text)
         character(len=*), intent(in) :: name
         character(len=:), allocatable :: text
         select case (name)
         case ('version'); text = 'the program version'
         case ('build'); text = 'the program (another build of usharp)'
         case ('input'); text = 'the input file'
         case ('constants'); text = 'the constants file (--constants)'
         case ('units'); text = "the layout of the journal's units"
         case default
            if (index(name, 'data:') == 1) then
               text = "the data file of test '"//name(6:)//"'"
            else if (index(name, 'history:') == 1) then
               text = "the control history of test '"//name(9:)//"'"
            else if (index(name, 'peaks:') == 1) then
               text = "the peak file of test '"//name(7:)//"'"
            else
               text = name
            end if
         end select
      end function describe
   end function fingerprint_mismatch
end module usharp_journal
