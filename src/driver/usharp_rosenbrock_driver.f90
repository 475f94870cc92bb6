!> Uniaxial simulation of the Miller model with a one-step linearly implicit method: the
!> Rosenbrock method RODAS4 of Hairer and Wanner (order 4 with an embedded order-3 error
!> estimate, L-stable, stiffly accurate; analytic Jacobian, one 3x3 LU per step). A one-step
!> method starts at full order after every corner of the load history, where CVODE's BDF
!> restarts at order 1; it stops exactly at each corner, so no step straddles a kink.
!> Output between steps: cubic Hermite interpolation of the state and its rates.
module usharp_rosenbrock_driver
   use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
   use usharp_kinds, only: dp
   use usharp_error, only: error_type, fatal_error, stat_failure
   use usharp_strings, only: str, real_str
   use usharp_miller, only: miller_model, uniaxial_rates
   use usharp_history, only: history_type, control_strain, segment_type
   use usharp_simulation, only: solver_options, sim_result, check_output_times
   implicit none
   private

   public :: simulate_rosenbrock, rates, rates_jacobian

   integer, parameter :: neq = 3, ns = 6

   !> RODAS4 (Hairer and Wanner 1996, Sec. IV.7) in the form G K_i = f(t + alpha_i h,
   !> y + sum_j a_ij K_j) + sum_j c_ij K_j / h + gamma_i h df/dt with G = I/(gamma h) - J;
   !> the step is y + sum_j m_j K_j and K_6 is the error estimate
   real(dp), parameter :: gam = 0.25_dp
   real(dp), parameter :: alpha(ns) = [0.0_dp, 0.386_dp, 0.21_dp, 0.63_dp, 1.0_dp, 1.0_dp]
   real(dp), parameter :: gamma_i(ns) = [0.25_dp, -0.1043_dp, 0.1035_dp, &
                                         -0.3620000000000023e-1_dp, 0.0_dp, 0.0_dp]
   !> Strictly lower triangles, row by row: (2,1), (3,1), (3,2), (4,1), ...
   real(dp), parameter :: a(15) = [0.1544e1_dp, 0.9466785280815826_dp, 0.2557011698983284_dp, &
      0.3314825187068521e1_dp, 0.2896124015972201e1_dp, 0.9986419139977817_dp, &
      0.1221224509226641e1_dp, 0.6019134481288629e1_dp, 0.1253708332932087e2_dp, &
      -0.6878860361058950_dp, 0.1221224509226641e1_dp, 0.6019134481288629e1_dp, &
      0.1253708332932087e2_dp, -0.6878860361058950_dp, 1.0_dp]
   real(dp), parameter :: c(15) = [-0.56688e1_dp, -0.2430093356833875e1_dp, &
      -0.2063599157091915_dp, -0.1073529058151375_dp, -0.9594562251023355e1_dp, &
      -0.2047028614809616e2_dp, 0.7496443313967647e1_dp, -0.1024680431464352e2_dp, &
      -0.3399990352819905e2_dp, 0.1170890893206160e2_dp, 0.8083246795921522e1_dp, &
      -0.7981132988064893e1_dp, -0.3152159432874371e2_dp, 0.1631930543123136e2_dp, &
      -0.6058818238834054e1_dp]
   real(dp), parameter :: m(ns) = [0.1221224509226641e1_dp, 0.6019134481288629e1_dp, &
      0.1253708332932087e2_dp, -0.6878860361058950_dp, 1.0_dp, 1.0_dp]

   !> Step-size control: safety factor, bounds of the change, and the order of the estimate
   real(dp), parameter :: safety = 0.9_dp, fac_min = 0.2_dp, fac_max = 6.0_dp, elo = 4.0_dp

contains

   !> Simulate the history from the virgin state, writing the response at the output times
   !> tout (s, non-decreasing, within the history's span); the plain model only
   subroutine simulate_rosenbrock(model, hist, tout, opts, res, error)
      type(miller_model), intent(in) :: model
      type(history_type), intent(in) :: hist
      real(dp), intent(in) :: tout(:)
      type(solver_options), intent(in) :: opts
      type(sim_result), intent(out) :: res
      type(error_type), allocatable, intent(out) :: error
      type(segment_type) :: seg
      real(dp) :: y(neq), f0(neq), y1(neq), f1(neq), atol(neq), t, h, t1, err, fac, hacc, erracc
      real(dp) :: rtol, atol_strain
      integer :: k, iout, nout, nseg, nstep, nacc
      logical :: ok, accept, rejected

      nout = size(tout)
      call res%allocate(nout)
      nseg = size(hist%t) - 1
      call check_output_times(hist, tout, error)
      if (allocated(error)) return
      y = [0.0_dp, 0.0_dp, model%d0]
      call opts%tolerances('rodas4', rtol, atol_strain)
      atol = [atol_strain, atol_strain*model%youngs, atol_strain*model%youngs]
      t = hist%t(1)
      iout = 1
      do while (iout <= nout)
         if (tout(iout) > t) exit
         call store(iout, y)
         iout = iout + 1
      end do
      seg = hist%segment(1)
      call rates(model, seg, t, y, f0, ok)
      res%nrhs = res%nrhs + 1
      if (.not. ok) then
         call fatal_error(error, 'integration failed at t = '//real_str(t, 'es12.5')// &
            ' s (rates not finite at the start)', stat_failure)
         return
      end if
      ! First step: a small fraction of the first segment; the control adapts it at once
      h = 1.0e-4_dp*(hist%t(2) - hist%t(1))
      nstep = 0
      do k = 1, nseg
         seg = hist%segment(k)
         t1 = hist%t(k + 1)
         rejected = .false.
         nacc = 0
         do while (t < t1)
            if (opts%max_step > 0.0_dp) h = min(h, opts%max_step)
            ! Land on the corner; avoid a sliver of a step just before it
            if (t + 1.05_dp*h >= t1) h = t1 - t
            call rodas_step(model, seg, t, y, f0, h, atol, rtol, y1, err, ok)
            res%njac = res%njac + 1
            res%nrhs = res%nrhs + 5
            accept = ok .and. err <= 1.0_dp
            if (accept) then
               ! The rates at the end: Hermite output and the next step's first stage
               call rates(model, seg, t + h, y1, f1, accept)
               res%nrhs = res%nrhs + 1
            end if
            if (.not. ok) then
               ! A stage left the model: shrink hard
               fac = 0.25_dp
            else if (accept) then
               ! Gustafsson's predictive control: where the error grows from step to step
               ! (entering the knee of a loop) shorten ahead of a rejection
               fac = step_factor(err)
               if (nacc > 0) fac = min(fac, min(fac_max, max(fac_min, &
                  (h/hacc)*safety*(erracc/max(err, 1.0e-10_dp)**2)**(1.0_dp/elo))))
            else if (err <= 1.0_dp) then
               ! The end point's rates failed
               fac = 0.25_dp
            else
               fac = step_factor(err)
            end if
            if (accept) then
               res%nsteps = res%nsteps + 1
               do while (iout <= nout)
                  if (tout(iout) > t + h*(1.0_dp + 1.0e-12_dp)) exit
                  call store(iout, hermite(t, h, y, f0, y1, f1, tout(iout)))
                  iout = iout + 1
                  ! max_steps counts the step attempts between two outputs, as for CVODE
                  nstep = 0
               end do
               if (h == t1 - t) then
                  t = t1
               else
                  t = t + h
               end if
               y = y1
               f0 = f1
               if (rejected) fac = min(fac, 1.0_dp)
               nacc = nacc + 1
               hacc = h
               erracc = max(1.0e-2_dp, err)
               rejected = .false.
            else
               rejected = .true.
            end if
            h = h*fac
            nstep = nstep + 1
            if (nstep > opts%max_steps .or. h < 1.0e-14_dp*max(1.0_dp, abs(t))) then
               call fatal_error(error, 'integration failed at t = '//real_str(t, 'es12.5')// &
                  ' s ('//trim(merge('too many steps      ', 'step size too small ', &
                  nstep > opts%max_steps))//')', stat_failure)
               return
            end if
         end do
      end do

   contains

      !> Standard step-size factor from the error norm
      pure real(dp) function step_factor(e) result(f)
         real(dp), intent(in) :: e
         f = min(fac_max, max(fac_min, safety*max(e, 1.0e-10_dp)**(-1.0_dp/elo)))
      end function step_factor

      subroutine store(i, ys)
         integer, intent(in) :: i
         real(dp), intent(in) :: ys(neq)
         call res%store(i, tout(i), hist%control, hist%value_at(tout(i)), model%youngs, ys(1), ys(2), ys(3))
      end subroutine store
   end subroutine simulate_rosenbrock

   !> One RODAS4 step of size h from (t, y) with f0 = f(t, y): the new state y1 and the
   !> weighted RMS norm err of the error estimate (accept when <= 1); ok false when a stage
   !> leaves the model (non-positive drag stress or rates not finite)
   pure subroutine rodas_step(model, seg, t, y, f0, h, atol, rtol, y1, err, ok)
      type(miller_model), intent(in) :: model
      type(segment_type), intent(in) :: seg
      real(dp), intent(in) :: t, y(neq), f0(neq), h, atol(neq), rtol
      real(dp), intent(out) :: y1(neq), err
      logical, intent(out) :: ok
      real(dp) :: jac(neq, neq), g(neq, neq), dfdt(neq), kst(neq, ns), ys(neq), rhs(neq), fs(neq)
      integer :: piv(neq), i, j, ij
      call rates_jacobian(model, seg, t, y, jac, dfdt)
      g = -jac
      do i = 1, neq
         g(i, i) = g(i, i) + 1.0_dp/(gam*h)
      end do
      call lu3(g, piv, ok)
      err = huge(1.0_dp)
      y1 = y
      if (.not. ok) return
      ij = 0
      do i = 1, ns
         if (i == 1) then
            fs = f0
         else
            ys = y
            do j = 1, i - 1
               ys = ys + a(ij + j)*kst(:, j)
            end do
            call rates(model, seg, t + alpha(i)*h, ys, fs, ok)
            if (.not. ok) return
         end if
         rhs = fs + gamma_i(i)*h*dfdt
         do j = 1, i - 1
            rhs = rhs + (c(ij + j)/h)*kst(:, j)
         end do
         if (i > 1) ij = ij + i - 1
         call lu3_solve(g, piv, rhs)
         kst(:, i) = rhs
      end do
      y1 = y
      do j = 1, ns
         y1 = y1 + m(j)*kst(:, j)
      end do
      ok = all(ieee_is_finite(y1)) .and. y1(3) > 0.0_dp
      if (.not. ok) return
      err = sqrt(sum((kst(:, ns)/(atol + rtol*max(abs(y), abs(y1))))**2)/neq)
   end subroutine rodas_step

   !> Stress, its derivative in eps_in and in time at (t, y)
   pure subroutine stress_of(model, seg, t, y, sigma, dsig, dsig_dt)
      type(miller_model), intent(in) :: model
      type(segment_type), intent(in) :: seg
      real(dp), intent(in) :: t, y(neq)
      real(dp), intent(out) :: sigma, dsig, dsig_dt
      real(dp) :: load
      load = seg%value(t)
      if (seg%control == control_strain) then
         sigma = model%youngs*(load - y(1))
         dsig = -model%youngs
         dsig_dt = model%youngs*seg%slope
      else
         sigma = load
         dsig = 0.0_dp
         dsig_dt = seg%slope
      end if
   end subroutine stress_of

   !> The rates (1/s, unit/s) at time t (s) and state y on segment seg; ok false outside the
   !> model (D <= 0) or when not finite
   pure subroutine rates(model, seg, t, y, f, ok)
      type(miller_model), intent(in) :: model
      type(segment_type), intent(in) :: seg
      real(dp), intent(in) :: t, y(neq)
      real(dp), intent(out) :: f(neq)
      logical, intent(out) :: ok
      real(dp) :: sigma, dsig, dsig_dt
      f = 0.0_dp
      ok = y(3) > 0.0_dp
      if (.not. ok) return
      call stress_of(model, seg, t, y, sigma, dsig, dsig_dt)
      call uniaxial_rates(model, sigma, dsig, y, f)
      ok = all(ieee_is_finite(f))
   end subroutine rates

   !> Jacobian in the state and the rates' time derivative (through the load), both from
   !> the analytic derivative in the stress: uniaxial_rates with d sigma/d eps_in = 1 gives
   !> d f/d sigma as its first column
   pure subroutine rates_jacobian(model, seg, t, y, jac, dfdt)
      type(miller_model), intent(in) :: model
      type(segment_type), intent(in) :: seg
      real(dp), intent(in) :: t, y(neq)
      real(dp), intent(out) :: jac(neq, neq), dfdt(neq)
      real(dp) :: sigma, dsig, dsig_dt, f(neq)
      call stress_of(model, seg, t, y, sigma, dsig, dsig_dt)
      call uniaxial_rates(model, sigma, 1.0_dp, y, f, jac)
      dfdt = jac(:, 1)*dsig_dt
      jac(:, 1) = jac(:, 1)*dsig
   end subroutine rates_jacobian

   !> Cubic Hermite interpolation at time s in [t, t + h] from the states and rates at both ends
   pure function hermite(t, h, y0, f0, y1, f1, s) result(ys)
      real(dp), intent(in) :: t, h, y0(neq), f0(neq), y1(neq), f1(neq), s
      real(dp) :: ys(neq)
      real(dp) :: u, h00, h10, h01, h11
      u = min(max((s - t)/h, 0.0_dp), 1.0_dp)
      h00 = (1.0_dp + 2.0_dp*u)*(1.0_dp - u)**2
      h10 = u*(1.0_dp - u)**2
      h01 = u*u*(3.0_dp - 2.0_dp*u)
      h11 = u*u*(u - 1.0_dp)
      ys = h00*y0 + h10*h*f0 + h01*y1 + h11*h*f1
   end function hermite

   !> LU factorisation with partial pivoting of a 3x3 matrix in place; ok false if singular
   pure subroutine lu3(g, piv, ok)
      real(dp), intent(inout) :: g(neq, neq)
      integer, intent(out) :: piv(neq)
      logical, intent(out) :: ok
      integer :: j, p, i
      real(dp) :: row(neq)
      ok = .true.
      do j = 1, neq
         p = j - 1 + maxloc(abs(g(j:, j)), 1)
         piv(j) = p
         if (g(p, j) == 0.0_dp) then
            ok = .false.
            return
         end if
         if (p /= j) then
            row = g(j, :)
            g(j, :) = g(p, :)
            g(p, :) = row
         end if
         do i = j + 1, neq
            g(i, j) = g(i, j)/g(j, j)
            g(i, j + 1:) = g(i, j + 1:) - g(i, j)*g(j, j + 1:)
         end do
      end do
   end subroutine lu3

   !> Solve with the factors of lu3
   pure subroutine lu3_solve(g, piv, b)
      real(dp), intent(in) :: g(neq, neq)
      integer, intent(in) :: piv(neq)
      real(dp), intent(inout) :: b(neq)
      integer :: j
      real(dp) :: s
      do j = 1, neq
         if (piv(j) /= j) then
            s = b(j)
            b(j) = b(piv(j))
            b(piv(j)) = s
         end if
      end do
      do j = 2, neq
         b(j) = b(j) - dot_product(g(j, :j - 1), b(:j - 1))
      end do
      do j = neq, 1, -1
         b(j) = (b(j) - dot_product(g(j, j + 1:), b(j + 1:)))/g(j, j)
      end do
   end subroutine lu3_solve
end module usharp_rosenbrock_driver
