!> Uniaxial simulation of a model (usharp_model) with CVODE (BDF, Newton, dense linear solver,
!> analytic Jacobian). The integration restarts at every corner of the load history, so no
!> step straddles a kink, and stops exactly at each corner. Optionally CVODES integrates the
!> forward sensitivities of the state to chosen constants alongside (staggered corrector,
!> sensitivities in the error test; their right-hand side is the analytic Jacobian times the
!> sensitivity plus the rates' derivative in the constant by central differences).
module usharp_cvode_driver
   use, intrinsic :: iso_c_binding
   use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
   use fcvodes_mod
   use fsundials_context_mod
   use fsundials_nvector_mod
   use fsundials_matrix_mod
   use fsundials_linearsolver_mod
   use fnvector_serial_mod
   use fsunmatrix_dense_mod
   use fsunlinsol_dense_mod
   use usharp_kinds, only: dp, i8
   use usharp_error, only: error_type, fatal_error, stat_failure
   use usharp_strings, only: str, real_str
   use usharp_model, only: model_type
   use usharp_effects, only: test_effects, extended_rates, lagged_value, lag_corners, &
                             extended_size, extended_initial
   use usharp_history, only: history_type, control_strain, segment_type
   use usharp_simulation, only: solver_options, sim_result, check_output_times
   implicit none
   private

   public :: simulate_cvode

   !> What the callbacks need: the model and the current linear segment of the load; with
   !> effects (extended) also the effects, the stiffness seen through the compliance, and
   !> the control's corners and lagged corner values
   type :: rhs_context
      class(model_type), allocatable :: model
      type(segment_type) :: line  !< the current segment of the load
      logical :: extended = .false.
      type(test_effects) :: eff
      real(dp) :: stiffness = 0.0_dp   !< E/(1 + kappa), model unit
      integer :: seg = 1
      real(dp), allocatable :: tc(:), vc(:), yk(:)
      !> The model's own states (the extended model adds p and R2)
      integer :: nm = 0
      !> The states that must stay positive (the model's positive_states)
      integer, allocatable :: positive(:)
      !> With sensitivities: the constants (physical units) and their indices (model order)
      real(dp), allocatable :: p(:)
      integer, allocatable :: pidx(:)
   end type rhs_context

contains

   !> Simulate the history from the virgin state, writing the response at the output times
   !> tout (s, non-decreasing, within the history's span). With effects, the extended model
   !> (usharp_effects) is integrated with a difference-quotient Jacobian: the model must then
   !> carry the effects' temperature and modulus already (effect_model), the initial state
   !> and the measured strain include R0, the drag offsets and the compliance, and the control
   !> value passes through the lag. The stress-channel shift is the caller's (output times).
   !> With sens (indices of constants, plain model only), deps_in(i, j) = d eps_in(tout(i)) /
   !> d c_sens(j) in 1/(unit of that constant); the drag stress's start D0 follows the constants.
   subroutine simulate_cvode(model, hist, tout, opts, res, error, effects, sens, deps_in)
      class(model_type), intent(in) :: model
      type(history_type), intent(in) :: hist
      real(dp), intent(in) :: tout(:)
      type(solver_options), intent(in) :: opts
      type(sim_result), intent(out) :: res
      type(error_type), allocatable, intent(out) :: error
      type(test_effects), intent(in), optional :: effects
      integer, intent(in), optional :: sens(:)
      real(dp), allocatable, intent(out), optional :: deps_in(:, :)

      type(rhs_context), target :: ctx
      type(c_ptr) :: sunctx, cvode_mem
      type(N_Vector), pointer :: yvec, abstol
      type(SUNMatrix), pointer :: amat
      type(SUNLinearSolver), pointer :: lsol
      real(c_double), allocatable, target :: y(:), atol(:)
      real(c_double) :: tret(1), tnext, rtol, atol_strain
      integer(c_int) :: ierr, n
      integer(c_long) :: counter(1)
      integer :: k, iout, nout, nseg, j, i
      integer(c_int) :: ns
      type(c_ptr) :: ys
      real(c_double), allocatable, target :: pbar(:)
      integer(c_int), allocatable, target :: plist(:)
      logical :: with_sens

      nout = size(tout)
      call res%allocate(nout)
      nseg = size(hist%t) - 1
      call check_output_times(hist, tout, error)
      if (allocated(error)) return
      call opts%tolerances('cvode', rtol, atol_strain)

      allocate (ctx%model, source=model)
      ctx%extended = present(effects)
      ctx%nm = model%n_uniaxial()
      ctx%positive = model%positive_states()
      if (ctx%extended) then
         n = int(extended_size(model), c_int)
         allocate (y(n), atol(n))
         ctx%eff = effects
         ctx%stiffness = model%youngs/(1.0_dp + effects%compliance)
         ctx%tc = hist%t
         ctx%vc = hist%v
         ctx%yk = lag_corners(hist%t, hist%v, effects%lag)
         call extended_initial(model, effects, y)
         ! p is a strain, R2 a stress
         atol(n - 1:n) = [atol_strain, atol_strain*model%youngs]
      else
         n = int(ctx%nm, c_int)
         allocate (y(n), atol(n))
         ctx%stiffness = model%youngs
         call model%uniaxial_initial(y)
      end if
      do i = 1, ctx%nm
         atol(i) = merge(atol_strain*model%youngs, atol_strain, model%uniaxial_is_stress(i))
      end do

      ierr = FSUNContext_Create(c_null_ptr, sunctx)
      yvec => FN_VMake_Serial(int(n, c_long), y, sunctx)
      abstol => FN_VMake_Serial(int(n, c_long), atol, sunctx)
      amat => FSUNDenseMatrix(int(n, c_long), int(n, c_long), sunctx)
      lsol => FSUNLinSol_Dense(yvec, amat, sunctx)
      cvode_mem = FCVodeCreate(CV_BDF, sunctx)
      ctx%line = hist%segment(1)
      ctx%seg = 1
      ierr = FCVodeInit(cvode_mem, c_funloc(rhs_fn), hist%t(1), yvec)
      ierr = ior(ierr, FCVodeSVtolerances(cvode_mem, rtol, abstol))
      ierr = ior(ierr, FCVodeSetUserData(cvode_mem, c_loc(ctx)))
      ierr = ior(ierr, FCVodeSetLinearSolver(cvode_mem, lsol, amat))
      if (.not. ctx%extended) ierr = ior(ierr, FCVodeSetJacFn(cvode_mem, c_funloc(jac_fn)))
      ierr = ior(ierr, FCVodeSetMaxNumSteps(cvode_mem, int(opts%max_steps, c_long)))
      if (opts%max_step > 0.0_dp) ierr = ior(ierr, FCVodeSetMaxStep(cvode_mem, opts%max_step))
      ierr = ior(ierr, FCVodeSetErrHandlerFn(cvode_mem, c_funloc(silent_handler), c_null_ptr))
      with_sens = present(sens) .and. present(deps_in) .and. .not. ctx%extended
      ns = 0
      if (with_sens) then
         ns = size(sens)
         allocate (deps_in(nout, ns))
         ctx%pidx = sens
         ctx%p = [(model%get_constant(sens(j)), j=1, ns)]
         pbar = abs(ctx%p)
         plist = [(int(j - 1, c_int), j=1, ns)]
         ys = FN_VCloneVectorArray(ns, yvec)
         call initial_sensitivities(model, sens, ys)
         ierr = ior(ierr, FCVodeSensInit1(cvode_mem, ns, CV_STAGGERED, c_funloc(sens_rhs), ys))
         ierr = ior(ierr, FCVodeSensEEtolerances(cvode_mem))
         ierr = ior(ierr, FCVodeSetSensErrCon(cvode_mem, 1_c_int))
         ierr = ior(ierr, FCVodeSetSensParams(cvode_mem, ctx%p, pbar, plist))
      end if
      if (ierr /= 0) then
         call fatal_error(error, 'CVODE could not be set up', stat_failure)
         call release()
         return
      end if

      iout = 1
      ! Outputs at the start time
      do while (iout <= nout)
         if (tout(iout) > hist%t(1)) exit
         call store(iout, hist%t(1))
         iout = iout + 1
      end do
      do k = 1, nseg
         if (k > 1) then
            call add_counts()
            ctx%line = hist%segment(k)
            ctx%seg = k
            ierr = FCVodeReInit(cvode_mem, hist%t(k), yvec)
            ! The sensitivities are continuous across the corner: go on from their values
            if (with_sens) ierr = FCVodeSensReInit(cvode_mem, CV_STAGGERED, ys)
         end if
         ierr = FCVodeSetStopTime(cvode_mem, hist%t(k + 1))
         ! Outputs inside this segment, then the corner itself
         do
            if (iout <= nout) then
               tnext = min(tout(iout), hist%t(k + 1))
            else
               tnext = hist%t(k + 1)
            end if
            ierr = FCVode(cvode_mem, tnext, yvec, tret, CV_NORMAL)
            if (ierr < 0 .or. .not. all(ieee_is_finite(y))) then
               call fatal_error(error, 'integration failed at t = '//real_str(tret(1), 'es12.5')// &
                  ' s (CVODE flag '//str(int(ierr))//': '//trim(flag_text(ierr))//')', stat_failure)
               call release()
               return
            end if
            if (with_sens) ierr = FCVodeGetSens(cvode_mem, tret, ys)
            do while (iout <= nout)
               if (tout(iout) > tret(1) + 1.0e-12_dp*max(1.0_dp, abs(tret(1)))) exit
               call store(iout, tout(iout))
               iout = iout + 1
            end do
            if (tret(1) >= hist%t(k + 1)) exit
         end do
      end do
      call add_counts()
      call release()

   contains

      !> ReInit resets CVODE's counters: add them up segment by segment
      subroutine add_counts()
         ierr = FCVodeGetNumSteps(cvode_mem, counter)
         res%nsteps = res%nsteps + counter(1)
         ierr = FCVodeGetNumRhsEvals(cvode_mem, counter)
         res%nrhs = res%nrhs + counter(1)
         ierr = FCVodeGetNumJacEvals(cvode_mem, counter)
         res%njac = res%njac + counter(1)
      end subroutine add_counts

      subroutine store(i, t)
         integer, intent(in) :: i
         real(dp), intent(in) :: t
         real(dp) :: load, rate, back, drag
         if (ctx%extended) then
            call lagged_value(ctx%tc, ctx%vc, ctx%yk, ctx%seg, ctx%eff%lag, t, load, rate)
         else
            load = hist%value_at(t)
         end if
         ! The measured strain includes the machine's kappa*sigma/E (the stiffness seen)
         call ctx%model%uniaxial_outputs(y(1:ctx%nm), back, drag)
         if (ctx%extended) back = back + y(n)
         call res%store(i, tout(i), hist%control, load, ctx%stiffness, y(1), back, drag)
         if (with_sens) then
            do j = 1, ns
               deps_in(i, j) = sens_value(ys, j, 1)
            end do
         end if
      end subroutine store

      subroutine release()
         if (with_sens) call FN_VDestroyVectorArray(ys, ns)
         call FCVodeFree(cvode_mem)
         ierr = FSUNLinSolFree(lsol)
         call FSUNMatDestroy(amat)
         call FN_VDestroy(yvec)
         call FN_VDestroy(abstol)
         ierr = FSUNContext_Free(sunctx)
      end subroutine release
   end subroutine simulate_cvode

   !> Start of the sensitivities: the virgin state's derivative in each constant by central
   !> differences of the models set up with it changed (the Miller model's D0 follows the
   !> constants unless it is fixed; its other states start at 0 whatever the constants)
   subroutine initial_sensitivities(model, sens, ys)
      class(model_type), intent(in) :: model
      integer, intent(in) :: sens(:)
      type(c_ptr), intent(in) :: ys
      type(N_Vector), pointer :: v
      real(c_double), pointer :: d(:)
      class(model_type), allocatable :: mp, mm
      type(error_type), allocatable :: err
      real(dp) :: c, h, y0p(model%n_uniaxial()), y0m(model%n_uniaxial())
      integer :: j
      do j = 1, size(sens)
         v => FN_VGetVecAtIndexVectorArray(ys, int(j - 1, c_int))
         d => FN_VGetArrayPointer(v)
         d = 0.0_dp
         c = model%get_constant(sens(j))
         h = 1.0e-6_dp*abs(c)
         allocate (mp, source=model)
         allocate (mm, source=model)
         call mp%set_constant(sens(j), c + h)
         call mm%set_constant(sens(j), c - h)
         call mp%setup(err)
         if (.not. allocated(err)) call mm%setup(err)
         if (.not. allocated(err)) then
            call mp%uniaxial_initial(y0p)
            call mm%uniaxial_initial(y0m)
            d = (y0p - y0m)/(2.0_dp*h)
         end if
         deallocate (mp, mm)
      end do
   end subroutine initial_sensitivities

   !> Component i of sensitivity vector j (1-based) of the vector array ys
   real(dp) function sens_value(ys, j, i) result(v)
      type(c_ptr), intent(in) :: ys
      integer, intent(in) :: j, i
      type(N_Vector), pointer :: nv
      real(c_double), pointer :: d(:)
      nv => FN_VGetVecAtIndexVectorArray(ys, int(j - 1, c_int))
      d => FN_VGetArrayPointer(nv)
      v = d(i)
   end function sens_value

   !> Stress and d(stress)/d(eps_in) for the state at time t
   pure subroutine stress_of(ctx, t, y, sigma, dsig)
      type(rhs_context), intent(in) :: ctx
      real(dp), intent(in) :: t, y(:)
      real(dp), intent(out) :: sigma, dsig
      real(dp) :: load, rate
      if (ctx%extended) then
         call lagged_value(ctx%tc, ctx%vc, ctx%yk, ctx%seg, ctx%eff%lag, t, load, rate)
      else
         load = ctx%line%value(t)
      end if
      if (ctx%line%control == control_strain) then
         sigma = ctx%stiffness*(load - y(1))
         dsig = -ctx%stiffness
      else
         sigma = load
         dsig = 0.0_dp
      end if
   end subroutine stress_of

   integer(c_int) function rhs_fn(t, yv, fv, udata) result(ierr) bind(C)
      real(c_double), value :: t
      type(N_Vector) :: yv, fv
      type(c_ptr), value :: udata
      type(rhs_context), pointer :: ctx
      real(c_double), pointer, contiguous :: y(:), f(:)
      real(dp) :: sigma, dsig
      integer :: i
      call c_f_pointer(udata, ctx)
      y => FN_VGetArrayPointer(yv)
      f => FN_VGetArrayPointer(fv)
      ! A state outside the model: let CVODE retry with a smaller step
      do i = 1, size(ctx%positive)
         if (.not. y(ctx%positive(i)) > 0.0_dp) then
            ierr = 1
            return
         end if
      end do
      call stress_of(ctx, t, y, sigma, dsig)
      if (ctx%extended) then
         call extended_rates(ctx%model, ctx%eff, sigma, y, f)
      else
         call ctx%model%uniaxial_rates(sigma, dsig, y, f)
      end if
      ierr = merge(0, 1, all(ieee_is_finite(f)))
   end function rhs_fn

   integer(c_int) function jac_fn(t, yv, fv, jmat, udata, tmp1, tmp2, tmp3) result(ierr) bind(C)
      real(c_double), value :: t
      type(N_Vector) :: yv, fv, tmp1, tmp2, tmp3
      type(SUNMatrix) :: jmat
      type(c_ptr), value :: udata
      type(rhs_context), pointer :: ctx
      real(c_double), pointer, contiguous :: y(:), jdata(:), jac(:, :)
      real(dp) :: sigma, dsig
      call c_f_pointer(udata, ctx)
      y => FN_VGetArrayPointer(yv)
      ! The binding's data pointer has length 1; view the column-major storage as n x n
      jdata => FSUNDenseMatrix_Data(jmat)
      call c_f_pointer(c_loc(jdata(1)), jac, [ctx%nm, ctx%nm])
      call stress_of(ctx, t, y, sigma, dsig)
      call plain_jacobian(ctx, sigma, dsig, y, jac)
      ierr = merge(0, 1, all(ieee_is_finite(jac)))
   end function jac_fn

   !> Right-hand side of sensitivity is (0-based): J s + df/dc, with the rates' derivative in
   !> the constant by central differences (relative step 1e-6; the rates are smooth in the
   !> constants, so its error is far below the integration's)
   integer(c_int) function sens_rhs(ns, t, yv, fv, is, ysv, ysdotv, udata, tmp1, tmp2) &
      result(ierr) bind(C)
      integer(c_int), value :: ns, is
      real(c_double), value :: t
      type(N_Vector) :: yv, fv, ysv, ysdotv, tmp1, tmp2
      type(c_ptr), value :: udata
      type(rhs_context), pointer :: ctx
      real(c_double), pointer, contiguous :: y(:), sv(:), sd(:)
      real(dp) :: sigma, dsig
      call c_f_pointer(udata, ctx)
      y => FN_VGetArrayPointer(yv)
      sv => FN_VGetArrayPointer(ysv)
      sd => FN_VGetArrayPointer(ysdotv)
      call stress_of(ctx, t, y, sigma, dsig)
      call sens_rates(ctx, is + 1, sigma, dsig, y, sv, sd)
      ierr = merge(0, 1, all(ieee_is_finite(sd)))
   end function sens_rhs

   !> The plain model's Jacobian (small arrays on the stack)
   subroutine plain_jacobian(ctx, sigma, dsig, y, jac)
      type(rhs_context), intent(in) :: ctx
      real(dp), intent(in) :: sigma, dsig
      real(dp), intent(in), contiguous :: y(:)
      real(dp), intent(out), contiguous :: jac(:, :)
      real(dp) :: ydot(size(y))
      call ctx%model%uniaxial_rates(sigma, dsig, y, ydot, jac)
   end subroutine plain_jacobian

   !> d/dt of sensitivity j: J s + d ydot/d c_j
   subroutine sens_rates(ctx, j, sigma, dsig, y, sv, sd)
      type(rhs_context), intent(in) :: ctx
      integer, intent(in) :: j
      real(dp), intent(in) :: sigma, dsig
      real(dp), intent(in), contiguous :: y(:), sv(:)
      real(dp), intent(out), contiguous :: sd(:)
      real(dp) :: f0(size(y)), dfdc(size(y)), jac(size(y), size(y))
      call ctx%model%uniaxial_rates(sigma, dsig, y, f0, jac)
      call ctx%model%rates_constant_derivative(ctx%pidx(j), sigma, dsig, y, dfdc)
      sd = matmul(jac, sv) + dfdc
   end subroutine sens_rates

   !> Keep CVODE quiet: failures come back as an error_type, printed once by the program
   subroutine silent_handler(error_code, module, function, msg, udata) bind(C)
      integer(c_int), value :: error_code
      type(c_ptr), value :: module, function, msg, udata
   end subroutine silent_handler

   pure function flag_text(flag) result(text)
      integer(c_int), intent(in) :: flag
      ! Fixed length: a deferred-length result is not thread-safe in gfortran 12 (the tests of
      ! a sensitivity Jacobian run on threads side by side)
      character(len=36) :: text
      select case (flag)
      case (CV_TOO_MUCH_WORK); text = 'too many steps'
      case (CV_TOO_MUCH_ACC); text = 'accuracy not reachable'
      case (CV_ERR_FAILURE); text = 'repeated error-test failures'
      case (CV_CONV_FAILURE); text = 'repeated Newton convergence failures'
      case (CV_RHSFUNC_FAIL, CV_REPTD_RHSFUNC_ERR, CV_UNREC_RHSFUNC_ERR)
         text = 'rates not finite'
      case (CV_LSETUP_FAIL, CV_LSOLVE_FAIL); text = 'linear solver failure'
      case default; text = 'solution not finite'
      end select
   end function flag_text
end module usharp_cvode_driver
