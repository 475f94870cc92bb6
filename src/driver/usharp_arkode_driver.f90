!> Uniaxial simulation of the plain Miller model with SUNDIALS's ARKODE: ARKStep, fully
!> implicit with an ESDIRK table (ARK4(3)6L[2]SA, order 4 with an embedded order 3, L-stable,
!> stiffly accurate), Newton with the dense linear solver and the analytic Jacobian. Like
!> RODAS4 it is a one-step method (no order-1 restart at a corner as CVODE's BDF) and stops
!> at the corners of the load (the turning points of a smooth forcing), where the integrator
!> is reset to go on from the state it reached. The rates and the Jacobian are RODAS4's
!> (usharp_rosenbrock_driver), so both integrate the same equations under the same forcing.
module usharp_arkode_driver
   use, intrinsic :: iso_c_binding
   use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
   use farkode_mod
   use farkode_arkstep_mod
   use fsundials_context_mod
   use fsundials_nvector_mod
   use fsundials_matrix_mod
   use fsundials_linearsolver_mod
   use fnvector_serial_mod
   use fsunmatrix_dense_mod
   use fsunlinsol_dense_mod
   use usharp_kinds, only: dp
   use usharp_error, only: error_type, fatal_error, stat_failure
   use usharp_strings, only: str, real_str
   use usharp_model, only: model_type
   use usharp_history, only: history_type
   use usharp_simulation, only: solver_options, sim_result, check_output_times
   use usharp_rosenbrock_driver, only: rate_system, rates, rates_jacobian, plain_system
   implicit none
   private

   public :: simulate_arkode

   !> The ESDIRK table
   character(len=*), parameter :: dirk_table = 'ARKODE_ARK436L2SA_DIRK_6_3_4'

contains

   !> Simulate the history from the virgin state with ARKODE, writing the response at the
   !> output times tout (s, non-decreasing, within the history's span). Tolerances: those of
   !> opts, RODAS4's defaults when not given.
   subroutine simulate_arkode(model, hist, tout, opts, res, error)
      class(model_type), intent(in) :: model
      type(history_type), intent(in) :: hist
      real(dp), intent(in) :: tout(:)
      type(solver_options), intent(in) :: opts
      type(sim_result), intent(out) :: res
      type(error_type), allocatable, intent(out) :: error
      ! A smooth forcing is followed on its spline's knots
      if (hist%smooth()) then
         call arkode_on(model, hist%forcing(), tout, opts, res, error)
      else
         call arkode_on(model, hist, tout, opts, res, error)
      end if
   end subroutine simulate_arkode

   !> simulate_arkode on hist: a piecewise-linear history, or a smooth one's knots
   subroutine arkode_on(model, hist, tout, opts, res, error)
      class(model_type), intent(in) :: model
      type(history_type), intent(in) :: hist
      real(dp), intent(in) :: tout(:)
      type(solver_options), intent(in) :: opts
      type(sim_result), intent(out) :: res
      type(error_type), allocatable, intent(out) :: error
      type(rate_system), target :: sys
      type(c_ptr) :: sunctx, mem
      type(N_Vector), pointer :: yvec, abstol
      type(SUNMatrix), pointer :: amat
      type(SUNLinearSolver), pointer :: lsol
      real(c_double), allocatable, target :: y(:), atol(:)
      real(c_double) :: tret(1), tnext, rtol, atol_strain
      integer(c_int) :: ierr
      integer(c_long) :: counter(1)
      integer, allocatable :: corner(:)
      integer :: j, iout, nout, i
      integer(c_int) :: neq

      nout = size(tout)
      call res%allocate(nout)
      call check_output_times(hist, tout, error)
      if (allocated(error)) return
      call opts%tolerances('rodas4', rtol, atol_strain)
      call plain_system(model, hist, sys)
      corner = hist%corners()
      sys%seg = hist%segment(1)
      sys%k = 1
      sys%kend = corner(2)
      neq = int(model%n_uniaxial(), c_int)
      allocate (y(neq), atol(neq))
      call model%uniaxial_initial(y)
      do i = 1, neq
         atol(i) = merge(atol_strain*model%youngs, atol_strain, model%uniaxial_is_stress(i))
      end do

      ierr = FSUNContext_Create(c_null_ptr, sunctx)
      yvec => FN_VMake_Serial(int(neq, c_long), y, sunctx)
      abstol => FN_VMake_Serial(int(neq, c_long), atol, sunctx)
      amat => FSUNDenseMatrix(int(neq, c_long), int(neq, c_long), sunctx)
      lsol => FSUNLinSol_Dense(yvec, amat, sunctx)
      mem = FARKStepCreate(c_null_funptr, c_funloc(rhs_fn), hist%t(1), yvec, sunctx)
      ierr = FARKStepSetTableName(mem, dirk_table, 'ARKODE_ERK_NONE')
      ierr = ior(ierr, FARKStepSVtolerances(mem, rtol, abstol))
      ierr = ior(ierr, FARKStepSetUserData(mem, c_loc(sys)))
      ierr = ior(ierr, FARKStepSetLinearSolver(mem, lsol, amat))
      ierr = ior(ierr, FARKStepSetJacFn(mem, c_funloc(jac_fn)))
      ierr = ior(ierr, FARKStepSetMaxNumSteps(mem, int(opts%max_steps, c_long)))
      if (opts%max_step > 0.0_dp) ierr = ior(ierr, FARKStepSetMaxStep(mem, opts%max_step))
      ierr = ior(ierr, FARKStepSetErrHandlerFn(mem, c_funloc(silent_handler), c_null_ptr))
      if (ierr /= 0) then
         call fatal_error(error, 'ARKODE could not be set up', stat_failure)
         call release()
         return
      end if

      iout = 1
      do while (iout <= nout)
         if (tout(iout) > hist%t(1)) exit
         call store(iout)
         iout = iout + 1
      end do
      do j = 1, size(corner) - 1
         sys%k = corner(j)
         sys%kend = corner(j + 1)
         sys%seg = hist%segment(corner(j))
         ! Past the first corner: go on from the state reached, without the step history
         if (j > 1) ierr = FARKStepReset(mem, hist%t(corner(j)), yvec)
         ierr = FARKStepSetStopTime(mem, hist%t(sys%kend))
         do
            if (iout <= nout) then
               tnext = min(tout(iout), hist%t(sys%kend))
            else
               tnext = hist%t(sys%kend)
            end if
            ierr = FARKStepEvolve(mem, tnext, yvec, tret, ARK_NORMAL)
            if (ierr < 0 .or. .not. all(ieee_is_finite(y))) then
               call fatal_error(error, 'integration failed at t = '//real_str(tret(1), 'es12.5')// &
                  ' s (ARKODE flag '//str(int(ierr))//')', stat_failure)
               call release()
               return
            end if
            do while (iout <= nout)
               if (tout(iout) > tret(1) + 1.0e-12_dp*max(1.0_dp, abs(tret(1)))) exit
               call store(iout)
               iout = iout + 1
            end do
            if (tret(1) >= hist%t(sys%kend)) exit
         end do
      end do
      ierr = FARKStepGetNumSteps(mem, counter)
      res%nsteps = counter(1)
      ierr = FARKStepGetNumJacEvals(mem, counter)
      res%njac = counter(1)
      call release()

   contains

      !> Output i from the state y (ARKODE interpolates it at the output time)
      subroutine store(i)
         integer, intent(in) :: i
         real(dp) :: back, drag
         call model%uniaxial_outputs(y, back, drag)
         call res%store(i, tout(i), hist%control, hist%value_at(tout(i)), sys%stiffness, &
                        y(1), back, drag)
      end subroutine store

      subroutine release()
         call FARKStepFree(mem)
         ierr = FSUNLinSolFree(lsol)
         call FSUNMatDestroy(amat)
         call FN_VDestroy(yvec)
         call FN_VDestroy(abstol)
         ierr = FSUNContext_Free(sunctx)
      end subroutine release
   end subroutine arkode_on

   !> The implicit rates; a state outside the model asks ARKODE for a smaller step
   integer(c_int) function rhs_fn(t, yv, fv, udata) result(ierr) bind(C, name='usharp_arkode_rhs')
      real(c_double), value :: t
      type(N_Vector) :: yv, fv
      type(c_ptr), value :: udata
      type(rate_system), pointer :: sys
      real(c_double), pointer, contiguous :: y(:), f(:)
      logical :: ok
      call c_f_pointer(udata, sys)
      y => FN_VGetArrayPointer(yv)
      f => FN_VGetArrayPointer(fv)
      call rates(sys, t, y, f, ok)
      ierr = merge(0, 1, ok)
   end function rhs_fn

   integer(c_int) function jac_fn(t, yv, fv, jmat, udata, tmp1, tmp2, tmp3) result(ierr) &
      bind(C, name='usharp_arkode_jac')
      real(c_double), value :: t
      type(N_Vector) :: yv, fv, tmp1, tmp2, tmp3
      type(SUNMatrix) :: jmat
      type(c_ptr), value :: udata
      type(rate_system), pointer :: sys
      real(c_double), pointer, contiguous :: y(:), jdata(:), jac(:, :)
      real(dp), allocatable :: dfdt(:)
      call c_f_pointer(udata, sys)
      y => FN_VGetArrayPointer(yv)
      allocate (dfdt(size(y)))
      ! The binding's data pointer has length 1; view the column-major storage as n x n
      jdata => FSUNDenseMatrix_Data(jmat)
      call c_f_pointer(c_loc(jdata(1)), jac, [size(y), size(y)])
      call rates_jacobian(sys, t, y, jac, dfdt)
      ierr = merge(0, 1, all(ieee_is_finite(jac)))
   end function jac_fn

   !> Keep ARKODE quiet: failures come back as an error_type
   subroutine silent_handler(error_code, module, function, msg, udata) &
      bind(C, name='usharp_arkode_silent')
      integer(c_int), value :: error_code
      type(c_ptr), value :: module, function, msg, udata
   end subroutine silent_handler
end module usharp_arkode_driver
