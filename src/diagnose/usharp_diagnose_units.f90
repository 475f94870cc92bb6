!> The expensive units of a diagnosis as units of its journal (usharp_diagnose_journal): a
!> Levenberg-Marquardt run and a set of starts, each computed, or replayed from the journal
!> with the same outcome and the same counts of simulations
module usharp_diagnose_units
   use usharp_kinds, only: dp
   use usharp_error, only: error_type
   use usharp_strings, only: str
   use usharp_optimiser, only: least_squares_type, optimum_type
   use usharp_levenberg, only: levenberg_marquardt
   use usharp_effect_problem, only: effect_problem
   use usharp_diagnose_numerics, only: best_of_starts
   use usharp_diagnose_journal, only: diagnose_journal, next_unit, record_unit, optimum_text, &
                                      read_optimum, reals_text, read_reals, text_lines
   implicit none
   private

   public :: lm_unit, starts_unit

contains

   !> levenberg_marquardt(obj, ...) as a unit of the journal jr (null: none)
   subroutine lm_unit(jr, obj, x0, lo, hi, h, ftol, itermax, max_evals, opt, error, jac0)
      type(diagnose_journal), pointer, intent(in) :: jr
      class(least_squares_type), intent(inout) :: obj
      real(dp), intent(in) :: x0(:), lo(:), hi(:), h, ftol
      integer, intent(in) :: itermax, max_evals
      type(optimum_type), intent(out) :: opt
      type(error_type), allocatable, intent(out) :: error
      real(dp), intent(in), optional :: jac0(:, :)
      type(error_type), allocatable :: e
      character(len=:), allocatable :: text, lines(:)
      logical :: replay
      integer :: n0, at, dn
      call next_unit(jr, text, replay, error)
      if (allocated(error)) return
      if (replay) then
         lines = text_lines(text)
         read (lines(1), *) dn
         at = 2
         call read_optimum(lines, at, opt, error)
         call add_evals(obj, dn)
         return
      end if
      n0 = evals_of(obj)
      call levenberg_marquardt(obj, x0, lo, hi, h, ftol, itermax, max_evals, opt, error, jac0)
      text = str(evals_of(obj) - n0)//new_line('a')//optimum_text(opt, error)
      call record_unit(jr, text, e)
      if (allocated(e)) call move_alloc(e, error)
   end subroutine lm_unit

   !> best_of_starts(ep, xs, ...) as a unit of the journal jr (null: none); error: a stop
   !> signal came first, or the journal cannot be written
   subroutine starts_unit(jr, ep, xs, lo, hi, h, max_evals, opt, nevals, error, fs, over_ranks)
      type(diagnose_journal), pointer, intent(in) :: jr
      type(effect_problem), intent(inout) :: ep
      real(dp), intent(in) :: xs(:, :), lo(:), hi(:), h
      integer, intent(in) :: max_evals
      type(optimum_type), intent(inout) :: opt
      integer, intent(inout) :: nevals
      type(error_type), allocatable, intent(out) :: error
      real(dp), intent(out), optional :: fs(:)
      logical, intent(in), optional :: over_ranks
      character(len=:), allocatable :: text, lines(:)
      real(dp), allocatable :: f(:)
      logical :: replay
      integer :: n0, nev0, at, dn, dnev
      call next_unit(jr, text, replay, error)
      if (allocated(error)) return
      if (replay) then
         lines = text_lines(text)
         read (lines(1), *) dn, dnev
         at = 2
         call read_optimum(lines, at, opt, error)
         ! (best_of_starts passes over a start that fails: it has no error of its own)
         if (allocated(error)) deallocate (error)
         call read_reals(lines, at, size(xs, 2), f)
         if (present(fs)) fs = f
         ep%nevals = ep%nevals + dn
         nevals = nevals + dnev
         return
      end if
      n0 = ep%nevals
      nev0 = nevals
      allocate (f(size(xs, 2)))
      call best_of_starts(ep, xs, lo, hi, h, max_evals, opt, nevals, f, over_ranks)
      if (present(fs)) fs = f
      text = str(ep%nevals - n0)//' '//str(nevals - nev0)//new_line('a')//optimum_text(opt, error)// &
             reals_text(f)
      call record_unit(jr, text, error)
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
