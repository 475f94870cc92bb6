!> The models usharp knows: &model name selects one. Adding a model is its module (an
!> extension of usharp_model's model_type) and one line in model_by_number below, with
!> n_models counting them.
module usharp_model_registry
   use usharp_error, only: error_type, fatal_error
   use usharp_strings, only: lower
   use usharp_model, only: model_type
   use usharp_model_miller, only: miller_model
   use usharp_model_chaboche, only: chaboche_model
   implicit none
   private

   public :: new_model, model_names, default_model, model_by_number, n_models

   !> Number of registered models
   integer, parameter :: n_models = 2
   !> The model &model name selects when it is not given
   character(len=*), parameter :: default_model = 'miller'

contains

   !> Model number i with its defaults
   subroutine model_by_number(i, model)
      integer, intent(in) :: i
      class(model_type), allocatable, intent(out) :: model
      select case (i)
      case (1); allocate (miller_model :: model)
      case (2); allocate (chaboche_model :: model)
      end select
   end subroutine model_by_number

   !> A new model of the given name (case-insensitive) with its defaults; an error naming
   !> the known models when there is none of that name
   subroutine new_model(name, model, error)
      character(len=*), intent(in) :: name
      class(model_type), allocatable, intent(out) :: model
      type(error_type), allocatable, intent(out) :: error
      integer :: i
      do i = 1, n_models
         call model_by_number(i, model)
         if (model%name() == lower(trim(adjustl(name)))) return
      end do
      deallocate (model)
      call fatal_error(error, "name = '"//trim(adjustl(name))//"' is not known (known: "// &
                       model_names()//')')
   end subroutine new_model

   !> The registered models' names, comma-separated
   function model_names() result(names)
      character(len=:), allocatable :: names
      class(model_type), allocatable :: model
      integer :: i
      names = ''
      do i = 1, n_models
         call model_by_number(i, model)
         if (i > 1) names = names//', '
         names = names//model%name()
      end do
   end function model_names
end module usharp_model_registry
