!> The expensive units of a diagnosis as units of its journal (usharp_diagnose_journal): a
!> Levenberg-Marquardt run and a set of starts, each computed, or replayed from the journal
!> with the same outcome and the same counts of simulations. With a memo (usharp_diagnose_memo)
!> a run made before is not made again: it takes no unit of the journal and no simulation.
module usharp_diagnose_units
   use usharp_kinds, only: dp
   use usharp_error, only: error_type
   use usharp_strings, only: str
   use usharp_optimiser, only: least_squares_type, optimum_type
   use usharp_levenberg, only: levenberg_marquardt
   use usharp_effect_problem, only: effect_problem
   use usharp_diagnose_numerics, only: best_of_starts, take_starts, lm_ftol, lm_itermax, lm_updates
   use usharp_diagnose_memo, only: run_memo, run_key, problem_key
   use usharp_diagnose_journal, only: diagnose_journal, next_unit, record_unit, optimum_text, &
                                      read_optimum, text_lines, unit_digest
   implicit none
   private

   public :: lm_unit, starts_unit

   type :: key_text
      character(len=:), allocatable :: s
   end type key_text

contains

   !> levenberg_marquardt(obj, ...) as a unit of the journal jr (null: none), or its outcome
   !> from memo when it ran before (an effect problem's run)
   subroutine lm_unit(jr, obj, x0, lo, hi, h, ftol, itermax, max_evals, opt, error, jac0, memo)
      type(diagnose_journal), pointer, intent(in) :: jr
      class(least_squares_type), intent(inout) :: obj
      real(dp), intent(in) :: x0(:), lo(:), hi(:), h, ftol
      integer, intent(in) :: itermax, max_evals
      type(optimum_type), intent(out) :: opt
      type(error_type), allocatable, intent(out) :: error
      real(dp), intent(in), optional :: jac0(:, :)
      type(run_memo), pointer, intent(in), optional :: memo
      type(error_type), allocatable :: e
      character(len=:), allocatable :: text, lines(:), key
      character(len=16) :: digest
      logical :: replay, memoised
      integer :: n0, at, dn, i
      memoised = .false.
      if (present(memo)) memoised = associated(memo)
      key = ''
      if (memoised .or. associated(jr)) then
         select type (obj)
         type is (effect_problem)
            key = run_key(problem_key(obj), min(max(x0, lo), hi), lo, hi, h, ftol, itermax, max_evals, &
                          present(jac0))
         class default
            key = run_key('residuals '//str(obj%nres()), min(max(x0, lo), hi), lo, hi, h, ftol, itermax, &
                          max_evals, present(jac0))
         end select
      end if
      ! The memo keeps runs of effect problems alone
      if (memoised) then
         select type (obj)
         type is (effect_problem)
         class default
            memoised = .false.
         end select
      end if
      if (memoised) then
         i = memo%find(key)
         if (i > 0) then
            ! made before: no evaluation now
            opt = memo%entries(i)%opt
            opt%nevals = 0
            return
         end if
      end if
      digest = unit_digest('lm '//key)
      call next_unit(jr, digest, text, replay, error)
      if (allocated(error)) return
      if (replay) then
         lines = text_lines(text)
         read (lines(1), *) dn
         at = 2
         call read_optimum(lines, at, opt, error)
         call add_evals(obj, dn)
      else
         n0 = evals_of(obj)
         call levenberg_marquardt(obj, x0, lo, hi, h, ftol, itermax, max_evals, opt, error, jac0, lm_updates)
         text = str(evals_of(obj) - n0)//new_line('a')//optimum_text(opt, error)
         call record_unit(jr, digest, text, e)
         if (allocated(e)) then
            call move_alloc(e, error)
            return
         end if
      end if
      if (memoised .and. .not. allocated(error)) call memo%add(key, opt)
   end subroutine lm_unit

   !> best_of_starts(ep, xs, ...) as a unit of the journal jr (null: none); error: a stop
   !> signal came first, or the journal cannot be written. With memo, the starts that ran
   !> before take their outcomes from it, and only the others run (none: no unit).
   subroutine starts_unit(jr, ep, xs, lo, hi, h, max_evals, opt, nevals, error, fs, over_ranks, memo, xe)
      type(diagnose_journal), pointer, intent(in) :: jr
      type(effect_problem), intent(inout) :: ep
      real(dp), intent(in) :: xs(:, :), lo(:), hi(:), h
      integer, intent(in) :: max_evals
      type(optimum_type), intent(inout) :: opt
      integer, intent(inout) :: nevals
      type(error_type), allocatable, intent(out) :: error
      real(dp), intent(out), optional :: fs(:)
      logical, intent(in), optional :: over_ranks
      type(run_memo), pointer, intent(in), optional :: memo
      !> each start's end point (a column; a start that failed: the start itself)
      real(dp), intent(out), optional :: xe(:, :)
      character(len=:), allocatable :: text, lines(:), problem, request
      character(len=16) :: digest
      type(key_text), allocatable :: keys(:)
      type(optimum_type), allocatable :: alts(:), run(:)
      type(optimum_type) :: none
      real(dp), allocatable :: f(:)
      logical, allocatable :: ok(:), known(:), run_ok(:)
      logical :: replay, memoised
      integer :: n0, nev0, at, dn, j, i, nrun, flag
      integer, allocatable :: cols(:)
      memoised = .false.
      if (present(memo)) memoised = associated(memo)
      allocate (alts(size(xs, 2)), ok(size(xs, 2)), known(size(xs, 2)), keys(size(xs, 2)))
      ok = .false.
      known = .false.
      if (memoised .or. associated(jr)) then
         problem = problem_key(ep)
         do j = 1, size(xs, 2)
            keys(j)%s = run_key(problem, min(max(xs(:, j), lo), hi), lo, hi, h, lm_ftol, lm_itermax, &
                                max_evals, .false.)
         end do
      end if
      if (memoised) then
         do j = 1, size(xs, 2)
            i = memo%find(keys(j)%s)
            if (i > 0) then
               alts(j) = memo%entries(i)%opt
               known(j) = .true.
               ok(j) = .true.
            end if
         end do
      end if
      cols = pack([(j, j=1, size(xs, 2))], .not. known)
      nrun = size(cols)
      if (nrun > 0) then
         request = 'starts'
         if (associated(jr)) then
            do i = 1, nrun
               request = request//new_line('a')//keys(cols(i))%s
            end do
         end if
         digest = unit_digest(request)
         call next_unit(jr, digest, text, replay, error)
         if (allocated(error)) return
         if (replay) then
            lines = text_lines(text)
            read (lines(1), *) dn
            at = 2
            do i = 1, nrun
               read (lines(at), *) flag
               at = at + 1
               if (flag == 1) then
                  call read_optimum(lines, at, alts(cols(i)), error)
                  if (allocated(error)) return
                  ok(cols(i)) = .true.
               end if
            end do
            ep%nevals = ep%nevals + dn
         else
            n0 = ep%nevals
            nev0 = 0
            allocate (run(nrun), run_ok(nrun))
            call best_of_starts(ep, xs(:, cols), lo, hi, h, max_evals, none, nev0, &
                                over_ranks=over_ranks, each=run, ran_ok=run_ok)
            text = str(ep%nevals - n0)//new_line('a')
            do i = 1, nrun
               text = text//str(merge(1, 0, run_ok(i)))//new_line('a')
               if (run_ok(i)) text = text//optimum_text(run(i), error)
               alts(cols(i)) = run(i)
               ok(cols(i)) = run_ok(i)
            end do
            call record_unit(jr, digest, text, error)
            if (allocated(error)) return
         end if
         if (memoised) then
            do i = 1, nrun
               if (ok(cols(i))) call memo%add(keys(cols(i))%s, alts(cols(i)))
            end do
         end if
      end if
      ! The starts taken from the memo ran before: their evaluations are not counted again
      allocate (f(size(xs, 2)))
      f = huge(1.0_dp)
      n0 = 0
      call take_starts(alts, ok, opt, n0, f)
      do j = 1, size(xs, 2)
         if (ok(j) .and. .not. known(j)) nevals = nevals + alts(j)%nevals
      end do
      if (present(fs)) fs = f
      if (present(xe)) then
         do j = 1, size(xs, 2)
            if (ok(j)) then
               xe(:, j) = alts(j)%x
            else
               xe(:, j) = xs(:, j)
            end if
         end do
      end if
   end subroutine starts_unit

   !> Simulations counted by the problem itself (effect problems count theirs)
   integer function evals_of(obj)
      class(least_squares_type), intent(in) :: obj
      evals_of = 0
      select type (obj)
      type is (effect_problem)
         evals_of = obj%nevals
      end select
   end function evals_of

   subroutine add_evals(obj, n)
      class(least_squares_type), intent(inout) :: obj
      integer, intent(in) :: n
      select type (obj)
      type is (effect_problem)
         obj%nevals = obj%nevals + n
      end select
   end subroutine add_evals
end module usharp_diagnose_units
