!> The last step of a diagnosis: when several effects explain the gap equally well, which
!> test would tell them apart. Candidates come from a standard set scaled to the fit tests
!> (tension at two rates, relaxation holds, cycling with holds at a smaller and a larger
!> range); each is simulated with every such effect's refit (its constants and parameters;
!> a per-test parameter at the fit tests' mean), and candidates are ranked for each pair by
!> the expected discrimination D = sum((y_a - y_b)**2)/s**2, s the noise the fit tests' data
!> show (relative to their peak) times the candidate's peak: the T-optimal criterion of
!> model discrimination (Atkinson and Fedorov 1975). D is a chi-square: above about 10 the
!> candidate would separate the pair at the noise of the data. The same ranking between two
!> end points of the leader's refit that the fit tests cannot tell apart, where they carry
!> different shares of the held-out gap, names the test that would fix what the fit tests
!> leave open of the effect's parameters.
module usharp_diagnose_separate
   use usharp_kinds, only: dp
   use usharp_error, only: error_type
   use usharp_strings, only: real_str
   use usharp_model, only: model_type
   use usharp_history, only: history_type, control_strain, tensile_history, relaxation_history, &
                             cyclic_history, output_times
   use usharp_simulation, only: sim_result, solver_options
   use usharp_effects, only: test_effects, effects_of, param_per_test, effect_nparams
   use usharp_effect_problem, only: simulate_effect
   use usharp_diagnose_numerics, only: bic_power
   use usharp_diagnose_types, only: diagnose_context, diagnose_result, effect_outcome, tell, &
                                    separation_type, n_candidates, prediction_open, separating_d
   implicit none
   private

   public :: separate, candidates, fit_amplitude, fit_rel_noise, finding_test


contains

   !> The diagnosis's last step: the tests that would tell apart the effects that explain the
   !> gap equally well (res%seps) and the leader's end points that leave its held-out
   !> prediction open (res%pin)
   subroutine separate(ctx, res)
      type(diagnose_context), intent(in) :: ctx
      type(diagnose_result), intent(inout) :: res
      res%separation = ''
      call separate_alike(ctx, res)
      call pin_open(ctx, res)
      res%verdict = res%verdict//res%separation
   end subroutine separate

   !> For each pair of the effects that explain the gap equally well (res%alike, at most the
   !> first three), the discrimination of each candidate test: res%seps
   subroutine separate_alike(ctx, res)
      type(diagnose_context), intent(in) :: ctx
      type(diagnose_result), intent(inout) :: res
      type(history_type) :: hist(n_candidates)
      character(len=80) :: names(n_candidates)
      type(separation_type), allocatable :: seps(:)
      real(dp) :: rel_noise
      integer :: na, i, j, npair, n
      allocate (seps(0))
      res%seps = seps
      if (.not. allocated(res%alike)) return
      na = min(size(res%alike), 3)
      if (na < 2) return
      call tell(ctx, 'which test would separate the effects', res%nevals)
      call candidates(fit_amplitude(ctx), hist, names)
      rel_noise = fit_rel_noise(ctx)
      npair = 0
      do i = 1, na - 1
         do j = i + 1, na
            npair = npair + 1
         end do
      end do
      deallocate (seps)
      allocate (seps(npair))
      npair = 0
      n = 0
      do i = 1, na - 1
         do j = i + 1, na
            npair = npair + 1
            seps(npair)%a = res%alike(i)
            seps(npair)%b = res%alike(j)
            call rank_candidates(ctx, res, hist, names, rel_noise, res%effects(res%alike(i)), &
                                 res%effects(res%alike(j)), seps(npair), n)
         end do
      end do
      res%seps = seps
      res%nevals = res%nevals + n
      associate (sp => seps(1))
         if (sp%d(sp%best) > 0.0_dp) res%separation = res%separation//'; a '//trim(sp%names(sp%best))// &
            ' would tell '//trim(res%effects(sp%a)%name)//' from '//trim(res%effects(sp%b)%name)// &
            ' (expected chi-square difference '//real_str(sp%d(sp%best), 'es9.2')//')'
      end associate
   end subroutine separate_alike

   !> Where the fit tests leave the leader's held-out prediction open (end points of its
   !> refit they cannot tell apart carry different shares of the held-out gap), the
   !> discrimination of each candidate test between the end points that carry the least and
   !> the most of it: the test that, added to the fit tests, would fix the effect's
   !> parameters where they matter to the held-out tests (res%pin). The verdict names it
   !> where its expected chi-square difference reaches separating_d, else says that no
   !> candidate would
   subroutine pin_open(ctx, res)
      type(diagnose_context), intent(in) :: ctx
      type(diagnose_result), intent(inout) :: res
      type(history_type) :: hist(n_candidates)
      character(len=80) :: names(n_candidates)
      type(effect_outcome) :: ends(2)
      type(separation_type) :: pin
      real(dp) :: rel_noise
      integer :: j, n
      res%pin = separation_type()
      if (res%leading == 0) return
      if (.not. prediction_open(res%effects(res%leading))) return
      if (.not. allocated(res%effects(res%leading)%c_open)) return
      call tell(ctx, 'which test would fix the held-out prediction', res%nevals)
      call candidates(fit_amplitude(ctx), hist, names)
      rel_noise = fit_rel_noise(ctx)
      associate (e => res%effects(res%leading))
         do j = 1, 2
            ends(j)%k = e%k
            ends(j)%c = e%c_open(:, j)
            ends(j)%p_all = e%p_open(:, j)
         end do
         pin%a = res%leading
         pin%b = res%leading
         n = 0
         call rank_candidates(ctx, res, hist, names, rel_noise, ends(1), ends(2), pin, n)
         res%nevals = res%nevals + n
         res%pin = pin
         if (pin%d(pin%best) >= separating_d) then
            res%separation = res%separation//'; a '//trim(names(pin%best))//' would tell those end points apart'
         else
            res%separation = res%separation//'; none of the candidate tests would tell those end points apart'
         end if
         res%separation = res%separation//' (expected chi-square difference '//real_str(pin%d(pin%best), 'es9.2')// &
                       ' between the two that carry '//real_str(100.0_dp*e%shrink_alike_lo, 'f0.1')// &
                       ' and '//real_str(100.0_dp*e%shrink_alike_hi, 'f0.1')//' %)'
      end associate
   end subroutine pin_open

   !> Each candidate's expected discrimination between the refits ea and eb, into sp (its
   !> names, d and best; a and b are the caller's)
   subroutine rank_candidates(ctx, res, hist, names, rel_noise, ea, eb, sp, nevals)
      type(diagnose_context), intent(in) :: ctx
      type(diagnose_result), intent(in) :: res
      type(history_type), intent(in) :: hist(n_candidates)
      character(len=80), intent(in) :: names(n_candidates)
      real(dp), intent(in) :: rel_noise
      type(effect_outcome), intent(in) :: ea, eb
      type(separation_type), intent(inout) :: sp
      integer, intent(inout) :: nevals   !< simulations, counted on
      integer :: c
      sp%names = names
      do c = 1, n_candidates
         call discrimination(ctx, res, hist(c), ea, eb, rel_noise, sp%d(c), nevals)
      end do
      sp%best = maxloc(sp%d, 1)
   end subroutine rank_candidates

   !> The standard candidates scaled to a strain amplitude emax: tension at two rates to
   !> twice it, relaxation holds at half and whole of it, cycling with holds over it and
   !> three times it
   subroutine candidates(emax, hist, names)
      real(dp), intent(in) :: emax
      type(history_type), intent(out) :: hist(:)
      character(len=80), intent(out) :: names(:)
      type(error_type), allocatable :: error
      call tensile_history(1.0e-3_dp, 2.0_dp*emax, hist(1), error)
      names(1) = 'tension at 1e-3 /s to '//real_str(200.0_dp*emax, 'f0.2')//' % strain'
      call tensile_history(1.0e-5_dp, 2.0_dp*emax, hist(2), error)
      names(2) = 'tension at 1e-5 /s to '//real_str(200.0_dp*emax, 'f0.2')//' % strain'
      call relaxation_history([0.5_dp*emax, emax], 1.0_dp, [600.0_dp, 600.0_dp], hist(3), error)
      names(3) = 'relaxation holds of 600 s at '//real_str(50.0_dp*emax, 'f0.2')//' and '// &
                 real_str(100.0_dp*emax, 'f0.2')//' % strain'
      call cyclic_history(emax, 0.0_dp, 1.0e-3_dp, 0.0_dp, 3, 300.0_dp, 300.0_dp, hist(4), error)
      names(4) = 'cycling at 1e-3 /s, range '//real_str(100.0_dp*emax, 'f0.2')//' %, 300 s holds, 3 cycles'
      call cyclic_history(3.0_dp*emax, 0.0_dp, 1.0e-3_dp, 0.0_dp, 3, 300.0_dp, 300.0_dp, hist(5), error)
      names(5) = 'cycling at 1e-3 /s, range '//real_str(300.0_dp*emax, 'f0.2')//' %, 300 s holds, 3 cycles'
   end subroutine candidates

   !> Expected discrimination of the candidate history between the refits of effects ea and
   !> eb (0 when either fails to simulate)
   subroutine discrimination(ctx, res, hist, ea, eb, rel_noise, d, nevals)
      type(diagnose_context), intent(in) :: ctx
      type(diagnose_result), intent(in) :: res
      type(history_type), intent(in) :: hist
      type(effect_outcome), intent(in) :: ea, eb
      real(dp), intent(in) :: rel_noise
      real(dp), intent(out) :: d
      integer, intent(inout) :: nevals
      real(dp), allocatable :: tout(:), ya(:), yb(:)
      real(dp) :: s
      logical :: oka, okb
      d = 0.0_dp
      tout = output_times(hist, max(hist%end_time()/400.0_dp, 0.1_dp))
      call response(ctx, res, hist, tout, ea, ya, oka)
      call response(ctx, res, hist, tout, eb, yb, okb)
      nevals = nevals + 2
      if (.not. (oka .and. okb)) return
      s = rel_noise*max(maxval(abs(ya)), tiny(1.0_dp))
      if (s <= 0.0_dp) return
      d = sum((ya - yb)**2)/s**2
   end subroutine discrimination

   !> Stress response to the strain history hist at times tout with effect e's refit
   subroutine response(ctx, res, hist, tout, e, y, ok)
      type(diagnose_context), intent(in) :: ctx
      type(diagnose_result), intent(in) :: res
      type(history_type), intent(in) :: hist
      real(dp), intent(in) :: tout(:)
      type(effect_outcome), intent(in) :: e
      real(dp), allocatable, intent(out) :: y(:)
      logical, intent(out) :: ok
      class(model_type), allocatable :: model
      type(test_effects) :: eff(1)
      type(error_type), allocatable :: error
      type(sim_result) :: sim
      real(dp), allocatable :: p(:)
      integer :: j, g, nt, np
      ok = .false.
      allocate (y(size(tout)))
      y = 0.0_dp
      if (.not. allocated(e%p_all) .or. .not. allocated(e%c)) return
      model = ctx%prob%cfg%model
      do j = 1, size(ctx%prob%idx)
         call model%set_constant(ctx%prob%idx(j), e%c(j))
      end do
      ! A per-test parameter of a new test: the fit tests' mean
      nt = size(ctx%prob%targets)
      associate (info => ctx%cat(e%k))
         np = info%nparam
         if (info%sharing == param_per_test) then
            allocate (p(np))
            do g = 1, np
               p(g) = sum(e%p_all((g - 1)*nt + 1:g*nt), .not. res%held)/max(count(.not. res%held), 1)
            end do
         else
            p = e%p_all(1:effect_nparams(info, 1))
         end if
      end associate
      eff = effects_of(e%k, p, 1, ctx%eff_base)
      call simulate_effect(model, eff(1), hist, tout, ctx%prob%cfg%solver, sim, error)
      if (allocated(error)) return
      y = sim%stress
      ok = all(abs(y) < huge(1.0_dp))
   end subroutine response

   !> The fit tests' largest strain amplitude (strain-controlled tests; 0.5 % when none)
   real(dp) function fit_amplitude(ctx) result(emax)
      type(diagnose_context), intent(in) :: ctx
      integer :: i
      emax = 0.0_dp
      do i = 1, size(ctx%ifit)
         associate (h => ctx%prob%cfg%tests(ctx%ifit(i))%hist)
            if (h%control == control_strain) emax = max(emax, maxval(abs(h%v)))
         end associate
      end do
      if (emax <= 0.0_dp) emax = 0.005_dp
   end function fit_amplitude

   !> The fit tests' noise (from the baseline's residual) relative to their peak, their mean
   real(dp) function fit_rel_noise(ctx) result(rel)
      type(diagnose_context), intent(in) :: ctx
      integer :: i
      rel = 0.0_dp
      do i = 1, size(ctx%ifit)
         associate (tg => ctx%prob%targets(ctx%ifit(i)))
            rel = rel + ctx%noise(ctx%ifit(i))/tg%y_ex_max
         end associate
      end do
      rel = rel/max(size(ctx%ifit), 1)
   end function fit_rel_noise

   !> Of the standard candidates scaled to emax (see candidates), the one that would find
   !> effect k with parameters p (one test's, physical units) with the highest power of the
   !> significance rule (q parameters, bic_power): the chi-square of its signal, the response
   !> with the effect less the response without, at rel_noise times the candidate's peak,
   !> sampled at about 400 points. model: its constants as fitted; temperature (K, when > 0)
   !> the candidates' in place of the model's. name '' when no candidate simulates.
   subroutine finding_test(model, k, p, base, solver, emax, rel_noise, q, name, power, nevals, temperature)
      class(model_type), intent(in) :: model
      integer, intent(in) :: k, q
      real(dp), intent(in) :: p(:), emax, rel_noise
      type(test_effects), intent(in) :: base
      type(solver_options), intent(in) :: solver
      character(len=80), intent(out) :: name
      real(dp), intent(out) :: power
      integer, intent(inout) :: nevals
      real(dp), intent(in), optional :: temperature
      type(history_type) :: hist(n_candidates)
      character(len=80) :: names(n_candidates)
      type(test_effects) :: eff(1)
      type(sim_result) :: s0, s1
      type(error_type), allocatable :: error
      real(dp), allocatable :: tout(:)
      real(dp) :: lambda, pc
      integer :: c
      name = ''
      power = -1.0_dp
      call candidates(emax, hist, names)
      eff = effects_of(k, p, 1, base)
      do c = 1, n_candidates
         tout = output_times(hist(c), max(hist(c)%end_time()/400.0_dp, 0.1_dp))
         call simulate_effect(model, base, hist(c), tout, solver, s0, error, temperature)
         if (allocated(error)) cycle
         call simulate_effect(model, eff(1), hist(c), tout, solver, s1, error, temperature)
         nevals = nevals + 2
         if (allocated(error)) cycle
         if (.not. all(abs(s1%stress) < huge(1.0_dp))) cycle
         lambda = sum((s1%stress - s0%stress)**2)/(rel_noise*max(maxval(abs(s0%stress)), tiny(1.0_dp)))**2
         pc = bic_power(lambda, q, size(tout))
         if (pc > power) then
            power = pc
            name = names(c)
         end if
      end do
   end subroutine finding_test
end module usharp_diagnose_separate
