!> The Levenberg-Marquardt runs a diagnosis has made, by what decides their outcome: a run
!> asked for again (the same effect problem, start, bounds and settings) takes the outcome
!> it had, which is the same bit for bit, without simulating. The stages of a diagnosis
!> reach the same start from different routes (a cross start from constants that another
!> refit left where it began; in the Alloy 617 diagnosis 43 of 426 runs, 9 % of its
!> simulations). Entries come from runs computed and from runs replayed from the journal
!> alike, so a resumed diagnosis meets the same entries as one that ran through.
module usharp_diagnose_memo
   use, intrinsic :: iso_fortran_env, only: int64
   use usharp_kinds, only: dp
   use usharp_strings, only: str
   use usharp_filesys, only: hash_text, hash_hex
   use usharp_optimiser, only: optimum_type
   use usharp_effect_values, only: test_effects, effect_reals
   use usharp_effect_problem, only: effect_problem
   implicit none
   private

   public :: run_memo, run_key, problem_key, effect_reals

   type :: memo_entry
      character(len=:), allocatable :: key
      type(optimum_type) :: opt
   end type memo_entry

   !> Outcomes of Levenberg-Marquardt runs by their key (run_key)
   type :: run_memo
      type(memo_entry), allocatable :: entries(:)
      integer :: n = 0
   contains
      procedure :: find => memo_find
      procedure :: add => memo_add
   end type run_memo

contains

   !> The index of the outcome kept under key (0: none)
   pure integer function memo_find(self, key) result(i)
      class(run_memo), intent(in) :: self
      character(len=*), intent(in) :: key
      do i = self%n, 1, -1
         if (self%entries(i)%key == key) return
      end do
      i = 0
   end function memo_find

   !> Keep opt under key (a key kept already keeps its outcome)
   pure subroutine memo_add(self, key, opt)
      class(run_memo), intent(inout) :: self
      character(len=*), intent(in) :: key
      type(optimum_type), intent(in) :: opt
      type(memo_entry), allocatable :: grown(:)
      if (self%find(key) > 0) return
      if (.not. allocated(self%entries)) allocate (self%entries(16))
      if (self%n == size(self%entries)) then
         allocate (grown(2*self%n))
         grown(:self%n) = self%entries
         call move_alloc(grown, self%entries)
      end if
      self%n = self%n + 1
      self%entries(self%n)%key = key
      self%entries(self%n)%opt = opt
   end subroutine memo_add

   !> What decides a Levenberg-Marquardt run of an effect problem from x0 (bounds lo, hi,
   !> difference step h, ftol, itermax, max_evals; with_jac0: the first Jacobian given);
   !> problem: problem_key of the effect problem
   pure function run_key(problem, x0, lo, hi, h, ftol, itermax, max_evals, with_jac0) result(key)
      character(len=*), intent(in) :: problem
      real(dp), intent(in) :: x0(:), lo(:), hi(:), h, ftol
      integer, intent(in) :: itermax, max_evals
      logical, intent(in) :: with_jac0
      character(len=:), allocatable :: key
      key = problem//' itermax '//str(itermax)//' max_evals '//str(max_evals)//' jac0 '// &
            merge('1', '0', with_jac0)//' search '//hex_text([x0, lo, hi, h, ftol])
   end function run_key

   !> What decides the residuals of ep: the effect and its parameters' set-up, the tests, and
   !> a digest of what their residuals are made from (data, weights, control histories, the
   !> model's constants, the integrator's settings)
   function problem_key(ep) result(key)
      type(effect_problem), intent(in) :: ep
      character(len=:), allocatable :: key
      character(len=:), allocatable :: made_of
      integer :: i, it
      made_of = reals_bytes([(ep%prob%cfg%model%get_constant(i), i=1, ep%prob%cfg%model%n_constants()), &
                             ep%prob%cfg%solver%rtol, ep%prob%cfg%solver%atol_strain, &
                             ep%prob%cfg%solver%max_step])// &
                ep%prob%cfg%solver%integrator//str(ep%prob%cfg%solver%max_steps)
      do i = 1, size(ep%tests)
         it = ep%tests(i)
         associate (tg => ep%prob%targets(it))
            made_of = made_of//reals_bytes([tg%t, tg%y_ex, tg%w, tg%y_ex_max])
         end associate
         if (allocated(ep%prob%cfg%tests(it)%hist%t)) &
            made_of = made_of//reals_bytes([ep%prob%cfg%tests(it)%hist%t, ep%prob%cfg%tests(it)%hist%v])
      end do
      key = 'effect '//str(ep%k)//' tests'//ints_text(ep%tests)//' constants'//ints_text(ep%prob%idx)// &
            ' free '//merge('1', '0', ep%free_constants)//' pfree'//ints_text(merge(1, 0, ep%pfree))// &
            ' pnonneg'//ints_text(merge(1, 0, ep%pnonneg))//' made of '//hash_hex(hash_text(made_of))// &
            ' parameters '//hex_text([ep%p0, ep%pscale, ep%pbox, effect_reals(ep%base)])
   end function problem_key

   pure function reals_bytes(x) result(bytes)
      real(dp), intent(in) :: x(:)
      character(len=8*size(x)) :: bytes
      bytes = transfer(x, bytes)
   end function reals_bytes

   !> x bit for bit, in hexadecimal
   pure function hex_text(x) result(text)
      real(dp), intent(in) :: x(:)
      character(len=17*size(x)) :: text
      integer :: j
      do j = 1, size(x)
         write (text(17*j - 16:17*j), '(z16.16,a)') transfer(x(j), 0_int64), ' '
      end do
   end function hex_text

   pure function ints_text(k) result(text)
      integer, intent(in) :: k(:)
      character(len=:), allocatable :: text
      integer :: j
      text = ''
      do j = 1, size(k)
         text = text//' '//str(k(j))
      end do
   end function ints_text
end module usharp_diagnose_memo
