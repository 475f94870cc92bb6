!> The checks every registered model must pass (docs/guide/new-model.md), run for each model
!> of usharp_model_registry with its default constants and conditions:
!> - the uniaxial rates' analytic Jacobian against central differences (relative 1e-6), under
!>   strain and stress control, at states along a strain cycle;
!> - the 3-D update's consistent tangent against central differences (relative 1e-6) at an
!>   inelastic increment with shear;
!> - the uniaxial driver (RODAS4) against the 3-D update's single element on the thesis's
!>   strain-controlled tests (within 5e-3 of peak: the update is backward Euler);
!> - the uniaxial driver at its default tolerances against a tight CVODE reference (1e-4 of
!>   peak).
module test_models
   use testdrive, only: error_type, unittest_type, new_unittest, check, test_failed
   use usharp_kinds, only: dp
   use usharp_error, only: uerror => error_type
   use usharp_model, only: model_type, update_status_ok
   use usharp_model_j2, only: solve_dense
   use usharp_model_registry, only: model_by_number, n_models
   use usharp_history, only: history_type, output_times, thesis_history
   use usharp_simulation, only: solver_options, sim_result
   use usharp_cvode_driver, only: simulate_cvode
   use usharp_rosenbrock_driver, only: simulate_rosenbrock
   use usharp_umat_driver, only: simulate_umat
   use usharp_config, only: run_config
   use usharp_input, only: read_config
   use usharp_objective, only: fit_problem
   use usharp_fit, only: run_fit, fit_outcome
   use usharp_model_miller, only: miller_model
   use usharp_effects, only: test_effects, extended_rates, wrapped_rates
   use test_design, only: synthetic_problem
   use test_util, only: write_text, scratch_dir
   use usharp_filesys, only: make_dir
   use usharp_strings, only: str, real_str
   implicit none
   private
   public :: collect_models, model_rates_jacobian, model_tangent, model_uniaxial_vs_update, &
             model_accuracy, fit_b_q_from_offset

   !> The checks' thresholds
   real(dp), parameter :: tol_derivative = 1.0e-6_dp, tol_update = 5.0e-3_dp, tol_accuracy = 1.0e-4_dp
   real(dp), parameter :: s2 = sqrt(2.0_dp)

contains

   subroutine collect_models(testsuite)
      type(unittest_type), allocatable, intent(out) :: testsuite(:)
      testsuite = [ &
         new_unittest('every-model-rates-jacobian-fd', test_jacobian), &
         new_unittest('every-model-tangent-fd', test_tangent), &
         new_unittest('every-model-uniaxial-driver-matches-3d-update', test_uniaxial_vs_update), &
         new_unittest('every-model-accuracy-tight-reference', test_accuracy), &
         new_unittest('effects-wrap-any-model', test_wrapped_rates), &
         new_unittest('q-from-tests-at-three-temperatures', test_q_three_temperatures)]
   end subroutine collect_models

   !> Run check on every registered model set up with its defaults; failures name the model
   subroutine every_model(error, checker)
      type(error_type), allocatable, intent(out) :: error
      interface
         subroutine checker(model, error)
            import :: model_type, error_type
            class(model_type), intent(in) :: model
            type(error_type), allocatable, intent(out) :: error
         end subroutine checker
      end interface
      class(model_type), allocatable :: model
      type(uerror), allocatable :: uerr
      integer :: i
      do i = 1, n_models
         call model_by_number(i, model)
         call model%setup(uerr)
         if (allocated(uerr)) then
            call test_failed(error, model%name()//': its defaults do not set up: '//uerr%message)
            return
         end if
         call checker(model, error)
         if (allocated(error)) then
            error%message = model%name()//': '//error%message
            return
         end if
      end do
   end subroutine every_model

   subroutine test_jacobian(error)
      type(error_type), allocatable, intent(out) :: error
      call every_model(error, model_rates_jacobian)
   end subroutine test_jacobian

   subroutine test_tangent(error)
      type(error_type), allocatable, intent(out) :: error
      call every_model(error, model_tangent)
   end subroutine test_tangent

   subroutine test_uniaxial_vs_update(error)
      type(error_type), allocatable, intent(out) :: error
      call every_model(error, model_uniaxial_vs_update)
   end subroutine test_uniaxial_vs_update

   subroutine test_accuracy(error)
      type(error_type), allocatable, intent(out) :: error
      call every_model(error, model_accuracy)
   end subroutine test_accuracy

   !> The analytic Jacobian of the uniaxial rates against central differences at states along
   !> a strain cycle (+-0.5 % at 1e-3/s, from the virgin state by backward Euler with the
   !> model's own Jacobian), with d sigma/d eps_in = -E (strain control) and 0 (stress control)
   subroutine model_rates_jacobian(model, error)
      class(model_type), intent(in) :: model
      type(error_type), allocatable, intent(out) :: error
      integer, parameter :: nstep = 400
      real(dp), parameter :: rate = 1.0e-3_dp, dt = 0.05_dp
      real(dp) :: y(model%n_uniaxial()), eps, sigma
      integer :: k, mode
      call model%uniaxial_initial(y)
      eps = 0.0_dp
      do k = 1, nstep
         ! 0 -> 0.5 % -> -0.5 % -> 0: a quarter, a half and a quarter of the steps
         if (k <= nstep/4 .or. k > 3*nstep/4) then
            eps = eps + rate*dt
         else
            eps = eps - rate*dt
         end if
         call implicit_step(model, eps, dt, y, error)
         if (allocated(error)) return
         if (mod(k, 20) /= 0) cycle
         do mode = 1, 2
            sigma = model%youngs*(eps - y(1))
            call jacobian_check(model, sigma, merge(-model%youngs, 0.0_dp, mode == 1), y, eps, error)
            if (allocated(error)) then
               error%message = 'step '//str(k)//merge(' (strain control): ', ' (stress control): ', &
                               mode == 1)//error%message
               return
            end if
         end do
      end do
   end subroutine model_rates_jacobian

   !> One backward Euler step of the uniaxial model under strain control to total strain eps
   subroutine implicit_step(model, eps, dt, y, error)
      class(model_type), intent(in) :: model
      real(dp), intent(in) :: eps, dt
      real(dp), intent(inout), contiguous :: y(:)
      type(error_type), allocatable, intent(out) :: error
      real(dp) :: y0(size(y)), f(size(y)), jac(size(y), size(y)), a(size(y), size(y)), r(size(y), 1)
      integer :: it, i, info
      y0 = y
      do it = 1, 50
         call model%uniaxial_rates(model%youngs*(eps - y(1)), -model%youngs, y, f, jac)
         r(:, 1) = -(y - y0 - dt*f)
         a = -dt*jac
         do i = 1, size(y)
            a(i, i) = a(i, i) + 1.0_dp
         end do
         call solve_dense(a, r, info)
         if (info /= 0) exit
         y = y + r(:, 1)
         if (maxval(abs(r(:, 1))/(abs(y) + 1.0e-6_dp)) < 1.0e-12_dp) return
      end do
      call test_failed(error, 'backward Euler on the uniaxial rates did not converge at strain '// &
                       real_str(eps, 'es10.3'))
   end subroutine implicit_step

   !> Jacobian at (sigma, y) against central differences, each row scaled by its largest entry
   !> times the state's scale (strain 1e-3, stresses E*1e-3)
   subroutine jacobian_check(model, sigma, dsig, y, eps, error)
      class(model_type), intent(in) :: model
      real(dp), intent(in) :: sigma, dsig, eps
      real(dp), intent(in), contiguous :: y(:)
      type(error_type), allocatable, intent(out) :: error
      real(dp) :: jac(size(y), size(y)), fd(size(y), size(y)), f0(size(y)), fp(size(y)), fm(size(y))
      real(dp) :: yp(size(y)), ym(size(y)), sc(size(y)), h, scale
      integer :: j
      do j = 1, size(y)
         sc(j) = merge(1.0e-3_dp*model%youngs, 1.0e-3_dp, model%uniaxial_is_stress(j))
      end do
      call model%uniaxial_rates(sigma, dsig, y, f0, jac)
      do j = 1, size(y)
         h = 1.0e-6_dp*max(abs(y(j)), sc(j))
         yp = y
         ym = y
         yp(j) = y(j) + h
         ym(j) = y(j) - h
         call model%uniaxial_rates(sigma + dsig*(yp(j) - y(j))*merge(1, 0, j == 1), dsig, yp, fp)
         call model%uniaxial_rates(sigma + dsig*(ym(j) - y(j))*merge(1, 0, j == 1), dsig, ym, fm)
         fd(:, j) = (fp - fm)/(2*h)
      end do
      do j = 1, size(y)
         scale = maxval(abs(fd(j, :)*sc))
         if (scale == 0.0_dp) cycle
         if (maxval(abs(jac(j, :) - fd(j, :))*sc)/scale > tol_derivative) then
            call test_failed(error, 'rates Jacobian row '//str(j)//' differs from central '// &
               'differences by '//real_str(maxval(abs(jac(j, :) - fd(j, :))*sc)/scale, 'es10.3')// &
               ' relative (strain '//real_str(eps, 'es10.3')//')')
            return
         end if
      end do
   end subroutine jacobian_check

   !> The consistent tangent against central differences of the update (strain step 1e-7) at
   !> an inelastic increment with shear, after tensile loading to 0.4 %
   subroutine model_tangent(model, error)
      class(model_type), intent(in) :: model
      type(error_type), allocatable, intent(out) :: error
      real(dp) :: y0(model%n_state()), y(model%n_state()), sig(6), c(6, 6), cd(6, 6), fd(6, 6)
      real(dp) :: sp(6), sm(6), eps0(6), deps(6), d(6), unit_strain(6), dev, nu
      integer :: k, j, st, nsub
      nu = 0.5_dp
      unit_strain = [1.0_dp, -nu, -nu, 0.0_dp, 0.0_dp, 0.0_dp]
      call model%state_initial(y0)
      eps0 = 0.0_dp
      ! Load in ten increments of 0.04 % in 1 s each (incompressible lateral guess)
      do k = 1, 10
         deps = 4.0e-4_dp*unit_strain
         call model%stress_update(eps0, deps, 1.0_dp, y0, sig, y, c, st, nsub)
         if (st /= update_status_ok) then
            call test_failed(error, 'the update did not converge while loading, increment '//str(k))
            return
         end if
         eps0 = eps0 + deps
         y0 = y
      end do
      deps = [2.0e-4_dp, -9.0e-5_dp, -9.0e-5_dp, s2*4.0e-5_dp, s2*1.0e-5_dp, 0.0_dp]
      call model%stress_update(eps0, deps, 0.15_dp, y0, sig, y, c, st, nsub)
      if (st /= update_status_ok) then
         call test_failed(error, 'the update did not converge')
         return
      end if
      do j = 1, 6
         d = 0.0_dp
         d(j) = 1.0e-7_dp
         call model%stress_update(eps0, deps + d, 0.15_dp, y0, sp, y, cd, st, nsub)
         call model%stress_update(eps0, deps - d, 0.15_dp, y0, sm, y, cd, st, nsub)
         fd(:, j) = (sp - sm)/(2*1.0e-7_dp)
      end do
      dev = maxval(abs(c - fd))/maxval(abs(fd))
      call check(error, dev <= tol_derivative, 'max |C - FD| / max |FD| = '//real_str(dev, 'es10.3'))
      if (allocated(error)) return
      ! The increment must be inelastic, or the check says nothing about the viscoplastic part
      call model%stress_update(eps0, deps, 0.15_dp, y0, sig, y, c, st, nsub)
      call check(error, maxval(abs(y(1:6) - y0(1:6))) > 1.0e-6_dp, &
                 'the increment of the tangent check is elastic: load the model further')
   end subroutine model_tangent

   !> RODAS4 on the uniaxial rates against the 3-D update's single element on the thesis's
   !> strain-controlled tests (LCF and relaxation)
   subroutine model_uniaxial_vs_update(model, error)
      class(model_type), intent(in) :: model
      type(error_type), allocatable, intent(out) :: error
      type(history_type) :: h
      type(sim_result) :: ru, rr
      type(solver_options) :: opts
      type(uerror), allocatable :: uerr
      real(dp), allocatable :: tout(:)
      real(dp) :: dev
      integer :: k
      do k = 1, 2
         call thesis_history(k, h, uerr)
         tout = output_times(h, 1.0_dp)
         call simulate_rosenbrock(model, h, tout, opts, rr, uerr)
         if (.not. allocated(uerr)) call simulate_umat(model, h, tout, opts, ru, uerr)
         if (allocated(uerr)) then
            call test_failed(error, 'thesis test '//str(k)//': '//uerr%message)
            return
         end if
         dev = maxval(abs(ru%stress - rr%stress))/maxval(abs(rr%stress))
         call check(error, dev <= tol_update, 'thesis test '//str(k)// &
                    ': max |3-D update - uniaxial| / peak = '//real_str(dev, 'es10.3'))
         if (allocated(error)) return
      end do
   end subroutine model_uniaxial_vs_update

   !> RODAS4 at its default tolerances against CVODE at rtol 1e-11, atol 1e-15 on the
   !> thesis's strain-controlled tests
   subroutine model_accuracy(model, error)
      class(model_type), intent(in) :: model
      type(error_type), allocatable, intent(out) :: error
      type(history_type) :: h
      type(sim_result) :: rr, ref
      type(solver_options) :: opts, tight
      type(uerror), allocatable :: uerr
      real(dp), allocatable :: tout(:)
      real(dp) :: dev
      integer :: k
      tight%integrator = 'cvode'
      tight%rtol = 1.0e-11_dp
      tight%atol_strain = 1.0e-15_dp
      do k = 1, 2
         call thesis_history(k, h, uerr)
         tout = output_times(h, 0.5_dp)
         call simulate_rosenbrock(model, h, tout, opts, rr, uerr)
         if (.not. allocated(uerr)) call simulate_cvode(model, h, tout, tight, ref, uerr)
         if (allocated(uerr)) then
            call test_failed(error, 'thesis test '//str(k)//': '//uerr%message)
            return
         end if
         dev = maxval(abs(rr%stress - ref%stress))/maxval(abs(ref%stress))
         call check(error, dev <= tol_accuracy, 'thesis test '//str(k)// &
                    ': max |RODAS4 - tight CVODE| / peak = '//real_str(dev, 'es10.3'))
         if (allocated(error)) return
      end do
   end subroutine model_accuracy

   !> The diagnosis's effects on any model (its rates driven by sigma - R2, with p and R2):
   !> for the Miller model, without softening, the same rates and Jacobian as its own
   !> extended form, within rounding, at states with a second back stress in both signs
   subroutine test_wrapped_rates(error)
      type(error_type), allocatable, intent(out) :: error
      type(miller_model) :: m
      type(uerror), allocatable :: uerr
      type(test_effects) :: eff
      real(dp) :: y(5), f1(5), f2(5), j1(5, 5), j2(5, 5), ys(5, 3)
      integer :: k
      call m%setup(uerr)
      eff%h3 = 100.0_dp
      eff%gamma3 = 300.0_dp
      ys = reshape([0.003_dp, 6.0_dp, 11.5_dp, 0.01_dp, 2.0_dp, &
                    -0.002_dp, -7.0_dp, 12.0_dp, 0.02_dp, -1.5_dp, &
                    0.0005_dp, 1.0_dp, 11.1_dp, 0.0_dp, 0.3_dp], [5, 3])
      do k = 1, 3
         y = ys(:, k)
         call extended_rates(m, eff, 20.0_dp*sign(1.0_dp, y(1)), y, f1, -m%youngs, j1)
         call wrapped_rates(m, eff, 20.0_dp*sign(1.0_dp, y(1)), y, f2, -m%youngs, j2)
         call check(error, all(abs(f1 - f2) <= 1.0e-10_dp*abs(f1) + 1.0e-14_dp*maxval(abs(f1))) &
                    .and. maxval(abs(j1 - j2))/maxval(abs(j1)) < 1.0e-10_dp, 'state '//str(k)// &
                    ': wrapped rates differ from the Miller extended form by '// &
                    real_str(maxval(abs(f1 - f2))/maxval(abs(f1)), 'es10.3')//' (rates), '// &
                    real_str(maxval(abs(j1 - j2))/maxval(abs(j1)), 'es10.3')//' (Jacobian)')
         if (allocated(error)) return
      end do
   end subroutine test_wrapped_rates

   !> Q, which enters only through theta(T), is determined by tests at several temperatures
   !> (&test temperature): synthetic Miller tests at 538, 593 and 649 C with 1 % noise, B and
   !> Q fitted from 2 B and 1.04 Q by Levenberg-Marquardt (usharp run's fit); Q within 2 %
   subroutine test_q_three_temperatures(error)
      type(error_type), allocatable, intent(out) :: error
      type(uerror), allocatable :: e
      type(run_config) :: cfg
      type(fit_problem) :: prob
      type(fit_outcome) :: out
      real(dp), parameter :: b_true = 1.0e15_dp, q_true = 91000.0_dp
      real(dp) :: q, diff
      call read_config(write_text('q-three-temperatures.nml', [character(len=100) :: &
         "&model temperature = 866.15, tm = 1800.0, youngs = 22.5e3 /", &
         "&constants a1 = 0.8, a2 = 7.42e-5, b = 1.0e15, c2 = 0.1, h1 = 280.0, h2 = 100.0,", &
         "  n = 5.8, q = 91000.0 /", &
         "&fit fitted = 'B', 'Q', method = 'lm' /", &
         "&test name = 't811', history = 'cyclic', strain_range = 0.01, strain_rate = 1e-3,", &
         "  cycles = 2, hold_max = 100.0, dt_out = 0.5, noise = 0.01, seed = 1,", &
         "  temperature = 811.15 /", &
         "&test name = 't866', history = 'cyclic', strain_range = 0.01, strain_rate = 1e-3,", &
         "  cycles = 2, hold_max = 100.0, dt_out = 0.5, noise = 0.01, seed = 2,", &
         "  temperature = 866.15 /", &
         "&test name = 't922', history = 'cyclic', strain_range = 0.01, strain_rate = 1e-3,", &
         "  cycles = 2, hold_max = 100.0, dt_out = 0.5, noise = 0.01, seed = 3,", &
         "  temperature = 922.15 /"]), cfg, e)
      if (.not. allocated(e)) call synthetic_problem(cfg, prob, e)
      if (allocated(e)) then
         call test_failed(error, e%message)
         return
      end if
      ! The responses must differ with temperature, or the check is void (the Miller model's
      ! D0 keeps the stress at the reference rate of the D0 formula the same at every
      ! temperature: the difference is in the rate dependence, the relaxation)
      diff = maxval(abs(prob%targets(1)%y_ex - prob%targets(3)%y_ex))/prob%targets(1)%y_ex_max
      call check(error, diff > 0.05_dp, 'the tests at 538 and 649 C differ by '// &
                 real_str(diff, 'es10.3')//' of the peak only')
      if (allocated(error)) return
      call fit_b_q_from_offset(prob, b_true, q_true, 'q-three-temperatures', out, e)
      if (allocated(e)) then
         call test_failed(error, e%message)
         return
      end if
      q = out%constants(2)
      write (*, '(4x,a)') 'B '//real_str(out%constants(1), 'es10.3')//' 1/s, Q '// &
         real_str(q, 'es10.3')//' cal/mol'
      call check(error, abs(q/q_true - 1.0_dp) <= 0.02_dp, 'Q fitted '//real_str(q, 'es10.3')// &
                 ' cal/mol, true '//real_str(q_true, 'es10.3')//' (start '// &
                 real_str(1.04_dp*q_true, 'es10.3')//'), B '//real_str(out%constants(1), 'es10.3'))
   end subroutine test_q_three_temperatures

   !> Fit B and Q (the fitted constants of prob, in that order) from 2 B and 1.04 Q, where the
   !> data were made with b_true (1/s) and q_true (cal/mol); the fit's logs in
   !> scratch_dir/name
   subroutine fit_b_q_from_offset(prob, b_true, q_true, name, out, e)
      type(fit_problem), intent(inout) :: prob
      real(dp), intent(in) :: b_true, q_true
      character(len=*), intent(in) :: name
      type(fit_outcome), intent(out) :: out
      type(uerror), allocatable, intent(out) :: e
      call prob%cfg%model%set_constant(prob%idx(1), 2.0_dp*b_true)
      call prob%cfg%model%set_constant(prob%idx(2), 1.04_dp*q_true)
      call prob%cfg%model%setup(e)
      if (.not. allocated(e)) call make_dir(scratch_dir//'/'//name, e)
      if (.not. allocated(e)) call run_fit(prob, scratch_dir//'/'//name, .false., out, e, force=.true.)
   end subroutine fit_b_q_from_offset
end module test_models
