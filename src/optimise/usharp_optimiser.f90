!> The interface every optimiser minimises through
module usharp_optimiser
   use usharp_kinds, only: dp
   use usharp_error, only: error_type
   implicit none
   private

   public :: objective_type, optimum_type, least_squares_type, reason_itermax, reason_max_evals

   !> optimum_type%reason of a search that stopped at its iteration limit, at its limit of
   !> evaluations
   character(len=*), parameter :: reason_itermax = 'itermax reached', reason_max_evals = 'max_evals reached'

   !> A scalar objective of a parameter vector. An error stops the optimiser at once.
   type, abstract :: objective_type
   contains
      procedure(eval_interface), deferred :: eval
   end type objective_type

   !> An objective that is a sum of squared residuals and can evaluate several points at once
   !> (independently: in parallel where the implementation can)
   type, abstract, extends(objective_type) :: least_squares_type
   contains
      procedure(residuals_interface), deferred :: residuals
      procedure(nres_interface), deferred :: nres
      procedure :: jacobian => no_jacobian
      procedure :: prefetch => no_prefetch
   end type least_squares_type

   abstract interface
      !> Residuals rs(:, j) and objective fs(j) = sum(rs(:, j)**2) at the points xs(:, j);
      !> ok(j) is .false. where the point was penalised (fs(j) then holds the penalty)
      subroutine residuals_interface(self, xs, rs, fs, ok, error)
         import :: least_squares_type, dp, error_type
         class(least_squares_type), intent(inout) :: self
         real(dp), intent(in) :: xs(:, :)
         real(dp), intent(out) :: rs(:, :)
         real(dp), intent(out) :: fs(:)
         logical, intent(out) :: ok(:)
         type(error_type), allocatable, intent(out) :: error
      end subroutine residuals_interface

      !> Number of residuals
      pure integer function nres_interface(self)
         import :: least_squares_type
         class(least_squares_type), intent(in) :: self
      end function nres_interface

      subroutine eval_interface(self, x, f, error)
         import :: objective_type, dp, error_type
         class(objective_type), intent(inout) :: self
         real(dp), intent(in) :: x(:)
         real(dp), intent(out) :: f
         type(error_type), allocatable, intent(out) :: error
      end subroutine eval_interface
   end interface

   !> What an optimiser returns
   type :: optimum_type
      real(dp), allocatable :: x(:)
      real(dp) :: f = huge(1.0_dp)
      integer :: nevals = 0
      integer :: iterations = 0
      character(len=:), allocatable :: reason  !< why it stopped
   end type optimum_type
contains

   !> Points the optimiser is likely to ask for next, as one batch (the difference Jacobian
   !> at a trial point, asked for if the trial is accepted): an objective may start
   !> simulating them with capacity that would idle otherwise. It changes no result: the
   !> optimiser asks for what it needs as before. By default nothing is done.
   subroutine no_prefetch(self, xs)
      class(least_squares_type), intent(inout) :: self
      real(dp), intent(in) :: xs(:, :)
      associate (unused => self, unused_xs => xs)
      end associate
   end subroutine no_prefetch

   !> The Jacobian d r / d x at x, where an objective can give it directly (done); by
   !> default it cannot, and the optimiser differences the residuals
   subroutine no_jacobian(self, x, jac, done, error)
      class(least_squares_type), intent(inout) :: self
      real(dp), intent(in) :: x(:)
      real(dp), intent(out) :: jac(:, :)
      logical, intent(out) :: done
      type(error_type), allocatable, intent(out) :: error
      jac = 0.0_dp
      done = .false.
   end subroutine no_jacobian

end module usharp_optimiser
