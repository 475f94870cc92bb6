!> The verdict of a diagnosis: which confirmed effect leads (the simplest of those the
!> evidence cannot tell apart), which explain the gap equally well, the words for it scaled
!> with the evidence, each refit's verdict, and the regions that carry the structured gap
module usharp_diagnose_verdict
   use usharp_kinds, only: dp
   use usharp_strings, only: real_str, str
   use usharp_math, only: log_dp
   use usharp_sort, only: order_of
   use usharp_effects, only: effect_info, effect_catalogue, n_effects, param_per_test
   use usharp_regions, only: region_stat
   use usharp_diagnose_options, only: bic_margin, corr_lag, correlated_ratio
   use usharp_forcing, only: noise_lag_ratio
   use usharp_distributions, only: chi2_isf
   use usharp_diagnose_types, only: diagnose_result, effect_outcome, fit_structured, held_quiet, prediction_open, &
                                    leaves_noise, explains_resolved, rest_at_noise, most, little, gap_fit_ref, &
                                    fit_effect_not_carried, form_beats_leader, joint_reason, &
                                    joint_bic_only, joint_held_fit, joint_form_beats, joint_loose, &
                                    joint_partial, hidden_effect, bound_list, params_bound_note, &
                                    hardening_note, joint_not_carried, held_rest_open, interval_text, deviance_change
   implicit none
   private

   !> Said of a set's share removed below most whose rest lies at the noise level
   character(len=*), parameter :: rest_note = ', the rest below its floor'
   !> A fall of BIC that is strong evidence but short of bic_margin (Kass and Raftery 1995:
   !> 6-10, a Bayes factor of 20-150): named in a verdict of no effect as a hint
   real(dp), parameter :: hint_margin = 6.0_dp

   !> The held-out tests against a leader at the constants of every test fitted together
   !> (see agreement_of)
   type :: agreement_type
      logical :: measured = .false.
      real(dp) :: share = 0.0_dp     !< share of the held-out gap removed, 1 = all
      real(dp) :: dev = 0.0_dp       !< the fit tests' deviance above their own fit
      real(dp) :: crit = 0.0_dp      !< its 95 % point
      integer :: nshared = 0         !< parameters the tests share
      logical :: agrees = .false.    !< most of the gap removed within the region, nothing alike
   end type agreement_type

   public :: conclude, verdict_of, top_regions, joint_verdict, power_cells, missed_note, alike_note, bound_note, &
             correlated_note, own_against_joint, carried_clause

contains

   !> The leading effect and the verdict in words. Among the confirmed effects, those whose
   !> BIC lies within bic_margin of the lowest (below it: no strong evidence, Kass and Raftery
   !> 1995, a Bayes factor under 150) or that leave both sets' structured gap at the noise
   !> level (nothing structured is left for a richer effect to explain) explain the gap
   !> equally well; the simplest of them leads (fewer parameters, global before per-test),
   !> then the lowest BIC
   subroutine conclude(res)
      type(diagnose_result), intent(inout) :: res
      integer :: j, best
      integer, allocatable :: conf(:), keys(:)
      logical, allocatable :: confirmed(:)
      res%leading = 0
      res%alike = [integer ::]
      ! The flags copied: a component of an array of derived type is not contiguous
      confirmed = res%effects%confirmed
      conf = pack([(j, j=1, size(res%effects))], confirmed)
      if (size(conf) == 0) then
         call no_effect(res)
         res%verdict = res%verdict//baseline_note(res)
         if (allocated(res%noise_corr)) res%verdict = res%verdict//correlated_note(res%names, res%noise_corr, &
                                                                                  'the baseline leaves')
         return
      end if
      best = conf(1)
      do j = 2, size(conf)
         if (res%effects(conf(j))%dbic < res%effects(best)%dbic) best = conf(j)
      end do
      do j = 1, size(conf)
         associate (e => res%effects(conf(j)))
            if (e%dbic < res%effects(best)%dbic + bic_margin .or. leaves_noise(e, res)) &
               res%alike = [res%alike, conf(j)]
         end associate
      end do
      ! Simplest first, ties by BIC (x/(1 + |x|) keeps its order within a step of the key)
      allocate (keys(size(res%alike)))
      do j = 1, size(res%alike)
         keys(j) = complexity(res%effects(res%alike(j)))
      end do
      res%alike = res%alike(order_of(real(keys, dp) + 1.0e-6_dp*squash(res%effects(res%alike)%dbic)))
      res%leading = res%alike(1)
      call lead_verdict(res, .false.)
   end subroutine conclude

   !> The verdict of the leader res%leading with the notes every verdict carries (serrated
   !> flow, the baseline, correlated residual, separating tests); agreed: the held-out tests agree with it at
   !> constants the fit tests allow (see agreement_of), which lets a partial carry explain
   subroutine lead_verdict(res, agreed)
      type(diagnose_result), intent(inout) :: res
      logical, intent(in) :: agreed
      call effect_verdict(res, agreed)
      res%verdict = res%verdict//serration_note(res)//baseline_note(res)
      ! The residual the leader leaves: a structured gap with sharp features (a lag's at each
      ! reversal) raises the ratio of the baseline's residual as correlated noise would
      if (allocated(res%effects(res%leading)%y) .and. allocated(res%y_ex)) then
         res%verdict = res%verdict//correlated_note(res%names, residual_correlation(res, &
                       res%effects(res%leading)%y), trim(res%effects(res%leading)%name)//' leaves')
      else if (allocated(res%noise_corr)) then
         res%verdict = res%verdict//correlated_note(res%names, res%noise_corr, 'the baseline leaves')
      end if
      if (allocated(res%separation)) res%verdict = res%verdict//res%separation
   end subroutine lead_verdict

   !> Per test, noise_sd of the residual y_ex - y from second differences corr_lag samples
   !> apart over that from neighbours (1 for independent noise; 0: too few points)
   pure function residual_correlation(res, y) result(ratio)
      type(diagnose_result), intent(in) :: res
      real(dp), intent(in) :: y(:)          !< a simulated response at every point (res%t)
      real(dp) :: ratio(size(res%names))
      integer :: i
      do i = 1, size(res%names)
         ratio(i) = noise_lag_ratio(pack(res%y_ex - y, res%test_of == i), corr_lag)
      end do
   end function residual_correlation

   !> The tests (names) whose residual that what leaves (the leading effect, the baseline) is
   !> correlated from sample to sample (ratio: see noise_correlation; above correlated_ratio),
   !> as a clause of a verdict ('' when none): noise so correlated reads smaller than it is,
   !> and the floors and BIC assume independent noise, so the evidence is overstated
   pure function correlated_note(names, ratio, what) result(text)
      character(len=*), intent(in) :: names(:)
      real(dp), intent(in) :: ratio(:)
      character(len=*), intent(in) :: what
      character(len=:), allocatable :: text, list
      integer :: j, n
      text = ''
      list = ''
      n = count(ratio > correlated_ratio)
      if (n == 0) return
      do j = 1, size(names)
         if (.not. ratio(j) > correlated_ratio) cycle
         if (len(list) > 0) list = list//', '
         list = list//trim(names(j))
      end do
      list = list//' that '//what//' is correlated from sample to sample (its sd from second '// &
             'differences '//str(corr_lag)//' samples apart '//real_str(minval(ratio, ratio > correlated_ratio), 'f0.1')
      if (n > 1) list = list//' to '//real_str(maxval(ratio), 'f0.1')
      text = '; the residual of '//list//' times that from neighbours, 1 for independent noise): noise '// &
             'so correlated reads smaller than it is, and the floors and BIC, which assume independent '// &
             'noise, overstate the evidence'
   end function correlated_note

   !> Every share and BIC is measured from the baseline: one that ran away (constants at a
   !> search bound) or did not converge is said in the verdict too, not only in its section
   pure function baseline_note(res) result(text)
      type(diagnose_result), intent(in) :: res
      character(len=:), allocatable :: text
      text = ''
      if (allocated(res%c_bound)) then
         if (any(res%c_bound /= 0)) text = '; measured from a baseline that ran away ('// &
            bound_list(res%cnames, res%c, res%c_bound)//' at a search bound of &fit)'
      end if
      if (len(text) == 0 .and. .not. res%baseline_converged) &
         text = '; measured from a baseline that had not converged'
   end function baseline_note

   !> The tests whose inelastic residual oscillates, named as serrated flow: no catalogue
   !> effect carries an oscillation, and its share of the gap can rank below a cycle's
   function serration_note(res) result(text)
      type(diagnose_result), intent(in) :: res
      character(len=:), allocatable :: text
      integer :: i
      text = ''
      if (.not. allocated(res%regions)) return
      do i = 1, size(res%regions)
         if (res%regions(i)%label /= 'serrated flow') cycle
         if (len(text) > 0) text = text//', '
         text = text//trim(res%regions(i)%test)
      end do
      if (len(text) > 0) text = '; serrated flow in '//text//': the residual of the inelastic '// &
         'points oscillates (as dynamic strain ageing makes it), which no catalogue effect carries'
   end function serration_note

   !> Complexity of an effect's refit: twice its free parameters, one more when they are per test
   pure integer function complexity(e) result(key)
      type(effect_outcome), intent(in) :: e
      type(effect_info) :: cat(n_effects)
      cat = effect_catalogue(1.0_dp)
      ! A parameter held at a chosen value (the second back stress's gamma3) is still one of
      ! the effect's form
      key = 2*(e%q + merge(1, 0, e%held)) + merge(1, 0, cat(e%k)%sharing == param_per_test)
   end function complexity

   !> The verdict when an effect leads: how much of the gap it explains, on which sets, what
   !> explains it as well, and which fit tests it makes worse; agreed: see lead_verdict
   subroutine effect_verdict(res, agreed)
      type(diagnose_result), intent(inout) :: res
      logical, intent(in) :: agreed
      character(len=:), allocatable :: text
      associate (e => res%effects(res%leading))
         if (agreed .or. explains_resolved(e, res)) then
            text = trim(e%name)//' explains the gap'
         else if (little_share(e, res)) then
            ! A few percent of a gap removed is a lower BIC, not an explanation
            text = trim(e%name)//' explains little of the gap'
         else
            text = trim(e%name)//' partly explains the gap'
         end if
         text = text//': BIC '//real_str(e%dbic, 'f0.1')
         if (.not. any(res%held) .and. .not. fit_structured(res)) then
            ! A share of a gap below its floor is no figure (0 % of 0): found by its own test
            text = text//'; the structured gap of every test fitted together lies below its '// &
                   'floor (the effect found by its own test, BIC)'
         else if (.not. any(res%held)) then
            text = text//', structured gap of every test fitted together removed '// &
                   real_str(100.0_dp*e%shrink_fit, 'f0.1')//' %'
         else if (.not. fit_structured(res) .and. held_quiet(res)) then
            ! Found by its own test (BIC) under the floors of the gap test, which asks of
            ! every direction of the residual at once
            text = text//'; both sets'' structured gaps lie below their floors, and the '// &
                   'held-out tests stay at the noise level with it'
         else
            text = text//', structured gap removed '//real_str(100.0_dp*e%shrink_fit, 'f0.1')// &
                   ' % on the fit tests'
            if (fit_structured(res) .and. e%shrink_fit < most .and. &
                rest_at_noise(gap_fit_ref(res), e%shrink_fit, res%floor_fit)) text = text//rest_note
            if (held_quiet(res)) then
               text = text//'; the held-out tests had none and still have none'
            else
               text = text//' and '//real_str(100.0_dp*e%shrink_held, 'f0.1')//' % on the held-out tests'
               if (e%shrink_held < most .and. rest_at_noise(res%gap_held, e%shrink_held, res%floor_held)) &
                  text = text//rest_note
               ! Per-test values of the held-out tests are fitted to them: no prediction
               if (e%held_fitted) text = text//' (by its values of the held-out tests fitted to them, '// &
                  'the constants carried over: not a prediction)'
               text = text//alike_note(e)
            end if
         end if
         text = text//size_note(res, e)
         if (size(res%alike) > 1) text = text//alike_text(res)
         if (allocated(e%p)) text = text//hardening_note(e%name, e%p)
         if (any(e%worse)) text = text//'; it makes '//test_list(res, e%worse)//' worse'
         text = text//bound_note(res, e)
         if (.not. e%resolved .and. allocated(e%p)) then
            if (size(e%p) > 0) text = text//'; its delay, '//real_str(e%p(1), 'g0.3')// &
               ' s, is below the sampling interval of the fit tests ('//real_str(res%dt_sample, 'g0.3')// &
               ' s): a lag of the rig and an offset between the time stamps of the channels explain it alike'
         end if
      end associate
      res%verdict = text
   end subroutine effect_verdict

   !> What the verdict says of the leader's size and where it acts: its fitted parameters
   !> with their 95 % intervals (of a per-test effect those of the tests that show it where
   !> its BIC counts only those, at most max_sized, the rest counted: all are in the refit's
   !> details; one at a search bound is left to bound_note), and, of the regions whose
   !> residual is structured, the one whose structured gap it removes most, with that gap
   !> before and after (not a held-out test's where its values there were fitted to it)
   function size_note(res, e) result(text)
      type(diagnose_result), intent(in) :: res
      type(effect_outcome), intent(in) :: e
      character(len=:), allocatable :: text
      integer, parameter :: max_sized = 3
      integer :: g, n, i
      logical :: lo_open, hi_open, shown_only
      real(dp) :: removed, most_removed
      text = ''
      if (allocated(e%p) .and. allocated(e%p_lo) .and. allocated(e%p_hi) .and. allocated(e%pname) .and. &
          allocated(e%punit)) then
         shown_only = allocated(e%shown_on) .and. allocated(e%p_counted)
         if (shown_only) shown_only = e%dbic < e%dbic_all
         n = 0
         do g = 1, size(e%p)
            if (shown_only .and. g <= size(e%p_counted)) then
               if (.not. e%p_counted(g)) cycle
            end if
            if (allocated(e%p_bound)) then
               if (g <= size(e%p_bound)) then
                  if (e%p_bound(g) /= 0) cycle
               end if
            end if
            n = n + 1
            if (n > max_sized) cycle
            lo_open = .false.
            hi_open = .false.
            if (allocated(e%p_lo_open) .and. allocated(e%p_hi_open)) then
               lo_open = e%p_lo_open(g)
               hi_open = e%p_hi_open(g)
            end if
            text = text//trim(merge('; fitted', ',       ', n == 1))//' '// &
                   interval_text(e%pname(g), e%p(g), e%p_lo(g), e%p_hi(g), lo_open, hi_open, 0, e%punit(g), &
                                 res%stress_unit)
         end do
         if (n > max_sized) text = text//' and '//str(n - max_sized)//' more'
      end if
      if (.not. allocated(e%regions) .or. .not. allocated(res%regions)) return
      if (size(e%regions) /= size(res%regions)) return
      most_removed = 0.0_dp
      n = 0
      do i = 1, size(res%regions)
         if (res%regions(i)%label == 'whole test' .or. .not. res%regions(i)%structured) cycle
         if (e%held_fitted .and. index(res%regions(i)%test, '(held out)') > 0) cycle
         removed = res%regions(i)%gap - e%regions(i)%gap
         if (removed > most_removed) then
            most_removed = removed
            n = i
         end if
      end do
      if (n > 0) text = text//'; it acts most on '//trim(res%regions(n)%test)//' '//trim(res%regions(n)%label)// &
         ' (structured gap '//real_str(res%regions(n)%gap, 'es9.2')//' -> '//real_str(e%regions(n)%gap, 'es9.2')//')'
   end function size_note

   !> What the verdict says of the other effects that explain the gap alike (res%alike): those
   !> within bic_margin of the leader's BIC equally well (the tests cannot tell them apart);
   !> those alike only because they too leave nothing but noise, with the BIC that does tell
   !> them apart (a lag 164 worse than a shift, both at the noise level, was once said to be
   !> indistinguishable); and why the leader leads: the simplest, or of equal complexity the
   !> lowest BIC
   function alike_text(res) result(text)
      type(diagnose_result), intent(in) :: res
      character(len=:), allocatable :: text
      character(len=:), allocatable :: within, noise, peers
      integer :: j, nw, nn
      within = ''
      noise = ''
      peers = lead_peers(res)
      nw = 0
      nn = 0
      associate (e => res%effects(res%leading))
         do j = 2, size(res%alike)
            associate (o => res%effects(res%alike(j)))
               if (abs(o%dbic - e%dbic) < bic_margin) then
                  if (nw > 0) within = within//', '
                  within = within//trim(o%name)
                  nw = nw + 1
               else
                  if (nn > 0) noise = noise//', '
                  noise = noise//trim(o%name)//' (BIC '//trim(merge('+', '-', o%dbic >= e%dbic))// &
                          real_str(abs(o%dbic - e%dbic), 'f0.1')//')'
                  nn = nn + 1
               end if
            end associate
         end do
         text = ''
         if (nw > 0) text = text//'; '//within//' explain'//trim(merge('s', ' ', nw == 1))// &
            ' it equally well (BIC within '//str(nint(bic_margin))//'): the tests cannot tell them apart'
         if (nn > 0) text = text//'; '//noise//' explain'//trim(merge('s', ' ', nn == 1))// &
            ' it to the noise level too: BIC tells '//trim(merge('it  ', 'them', nn == 1))//' from '// &
            trim(e%name)//', the noise level does not rule '//trim(merge('it  ', 'them', nn == 1))//' out'
         ! (the simplest leads whatever a richer effect's BIC: of equal complexity, the lowest)
         if (len(peers) == 0) then
            text = text//'; '//trim(e%name)//' is the simplest'
         else
            text = text//'; '//trim(e%name)//' is the simplest with '//peers//', and leads by BIC among those'
         end if
      end associate
   end function alike_text

   !> The effects alike with the leader (res%alike) that are as simple as it, by name ('' where
   !> the leader is the simplest): among those it leads by BIC, not by simplicity
   function lead_peers(res) result(peers)
      type(diagnose_result), intent(in) :: res
      character(len=:), allocatable :: peers
      integer :: j
      peers = ''
      do j = 2, size(res%alike)
         associate (o => res%effects(res%alike(j)))
            if (complexity(o) > complexity(res%effects(res%leading))) cycle
            if (len(peers) > 0) peers = peers//', '
            peers = peers//trim(o%name)
         end associate
      end do
   end function lead_peers

   !> What the effect carried to the held-out tests (see held_own in usharp_diagnose) does on
   !> the fit tests and the held-out tests, for the verdict and the report alike
   function carried_clause(e) result(text)
      type(effect_outcome), intent(in) :: e
      character(len=:), allocatable :: text
      text = trim(e%name)//' explains the fit tests (BIC '//real_str(e%dbic, 'f0.1')//', '// &
             real_str(100.0_dp*e%shrink_fit, 'f0.1')//' % of their structured gap) but does not carry to the '// &
             'held-out tests ('//real_str(100.0_dp*e%shrink_held, 'f0.1')//' % of their gap'// &
             trim(merge(': worse', '       ', e%shrink_held < 0.0_dp))//')'
   end function carried_clause

   !> What the verdict adds of a leader's refit that ran to a search bound: its constants at
   !> a bound of &fit (the refit ran away), its own parameters at theirs (not determined);
   !> '' when none did (the report had flagged a backstress2 with H3 at its bound and A1, B
   !> at the box's while the verdict read as if the refit had settled)
   function bound_note(res, e) result(text)
      type(diagnose_result), intent(in) :: res
      type(effect_outcome), intent(in) :: e
      character(len=:), allocatable :: text
      text = ''
      if (allocated(e%c_bound) .and. allocated(e%c) .and. allocated(res%cnames)) then
         if (any(e%c_bound /= 0)) text = '; its refit ran away: '//bound_list(res%cnames, e%c, e%c_bound)// &
            ' at a search bound of &fit'
      end if
      if (allocated(e%p_bound) .and. allocated(e%pname) .and. allocated(e%p) .and. allocated(e%punit)) &
         text = text//params_bound_note(e%pname, e%p, e%p_bound, e%punit, res%stress_unit)
   end function bound_note

   !> The verdict of a diagnosis whose prediction could not decide (see joint_reason), from
   !> its joint stage (jres: every test fitted): an effect the joint stage confirms leads,
   !> said to rest on a fit to the tests it explains and not on a prediction, with why the
   !> prediction could not decide; a joint baseline at the noise level says the held-out gap
   !> came from the constants the fit tests leave loose. A leader that carried part of the
   !> held-out gap stays, with what every test fitted together makes of it.
   subroutine joint_verdict(res, jres)
      type(diagnose_result), intent(inout) :: res
      type(diagnose_result), intent(in) :: jres
      integer :: n, why
      type(agreement_type) :: ag
      why = joint_reason(res, .false.)
      if (why == joint_partial) then
         ! Where the held-out tests agree with the leader at constants the fit tests allow, what
         ! its prediction left is what the fit tests leave open: it explains the gap
         ag = agreement_of(res, jres)
         if (ag%agrees) call lead_verdict(res, .true.)
         res%verdict = res%verdict//'; '//carry_note(res, jres, ag)
      else if (jres%leading > 0) then
         n = len_trim(jres%effects(jres%leading)%name)
         res%verdict = jres%verdict(:n)//' (fitted with the held-out tests: '//why_note(res, why)// &
                       ')'//jres%verdict(n + 1:)
      else if (.not. fit_structured(jres)) then
         res%verdict = 'no significant effect: fitted together with the fit tests, the held-out '// &
            'tests too are at the noise level (structured gap '//real_str(jres%gap_fit, 'es9.2')// &
            ' against its floor '//real_str(jres%floor_fit, 'es9.2')//'): their predicted gap '// &
            'comes from constants the fit tests alone leave loose, not from a missing effect'// &
            serration_note(res)//suggested_note(jres)//stage_missed_note(jres)
         select case (why)
         case (joint_bic_only)
            res%verdict = res%verdict//'; '//trim(res%effects(res%leading)%name)// &
               ' led by BIC on the fit tests alone, which every test fitted together does not bear out'
         case (joint_held_fit)
            res%verdict = res%verdict//'; '//held_fit_note(res)//', which every test fitted together '// &
               'does not bear out'
         case (joint_form_beats)
            res%verdict = res%verdict//'; '//beaten_note(res)
         end select
      else
         res%verdict = res%verdict//'; with the held-out tests fitted too, '//jres%verdict
      end if
   end subroutine joint_verdict

   !> The held-out tests' own differences beside the carried effect (see held_own in
   !> usharp_diagnose) against the leader of every test fitted together, as a clause ('' where
   !> either is missing): both account for every test, the first with the carried effect at
   !> the fit tests' constants and each held-out test's own effect on top, the second with
   !> one effect fitted to every test. BIC over every test's points (each test's residuals
   !> of a variance of their own) says which the data prefer. The first's constants are the
   !> fit tests' alone, so it is the one put at a disadvantage.
   function own_against_joint(res) result(text)
      type(diagnose_result), intent(in) :: res
      character(len=:), allocatable :: text
      real(dp), allocatable :: two(:)
      real(dp) :: dbic
      integer :: i
      text = ''
      if (res%own_base == 0 .or. .not. allocated(res%own_f) .or. .not. allocated(res%joint)) return
      if (res%joint%leading == 0 .or. .not. (allocated(res%npts) .and. allocated(res%held))) return
      associate (e => res%effects(res%own_base), je => res%joint%effects(res%joint%leading))
         if (.not. (allocated(e%per_test_after) .and. allocated(je%per_test_after))) return
         if (size(e%per_test_after) /= size(res%npts) .or. size(je%per_test_after) /= size(res%npts) .or. &
             count(res%held) /= size(res%own_f)) return
         two = e%per_test_after
         two(pack([(i, i=1, size(two))], res%held)) = res%own_f
         dbic = deviance_change(res%npts, je%per_test_after, two) + &
                real(e%q + res%own_q - je%q, dp)*log_dp(real(sum(res%npts), dp))
         if (dbic < -bic_margin) then
            text = '; the two together fit every test better than '//trim(je%name)//' alone, which every test '// &
                   'fitted together names (BIC '//real_str(dbic, 'f0.1')//' against it)'
         else if (dbic > bic_margin) then
            text = '; '//trim(je%name)//' alone, which every test fitted together names, fits them better than '// &
                   'the two together (BIC '//real_str(-dbic, 'f0.1')//' against them): the held-out tests need no '// &
                   'difference of their own'
         else
            text = '; '//trim(je%name)//' alone, which every test fitted together names, fits them as well as the '// &
                   'two together (BIC within '//str(nint(bic_margin))//')'
         end if
      end associate
   end function own_against_joint

   !> Why the prediction of a diagnosis could not decide (see joint_reason), as a clause
   function why_note(res, why) result(text)
      type(diagnose_result), intent(in) :: res
      integer, intent(in) :: why
      character(len=:), allocatable :: text
      select case (why)
      case (joint_bic_only)
         associate (e => res%effects(res%leading))
            text = 'on the fit tests alone '//trim(e%name)//' led by BIC '//real_str(e%dbic, 'f0.1')
            if (fit_structured(res)) then
               text = text//', removing '//real_str(100.0_dp*e%shrink_fit, 'f0.1')//' % of their '// &
                      'structured gap, with the held-out tests below their floor'
            else
               text = text//' with both sets'' structured gaps below their floors'
            end if
            text = text//', which the prediction cannot confirm'
         end associate
      case (joint_held_fit)
         text = held_fit_note(res)
      case (joint_form_beats)
         text = beaten_note(res)
      case (joint_loose)
         text = 'the prediction of the held-out tests that named '//trim(res%effects(res%leading)%name)// &
                ' rests on constants the fit tests leave at a search bound, so it tests those constants '// &
                'as much as the effect'
      case (joint_not_carried)
         text = 'fitted to the fit tests alone, no effect of a plausible magnitude took their structured '// &
                'gap to its floor and none was confirmed on the held-out tests, so their prediction cannot '// &
                'confirm it'
      case default
         if (fit_effect_not_carried(res)) then
            text = 'fitted to the fit tests alone, the effects that explain them do not carry to the '// &
                   'held-out tests, so their prediction cannot confirm it'
         else
            text = 'the fit tests alone show no structured gap that an effect explains, so their '// &
                   'prediction cannot confirm it'
         end if
      end select
   end function why_note

   !> What every test fitted together (jres) makes of a leader that carried only part of the
   !> held-out gap (see partial_carry), as a clause: the same effect closing every gap says
   !> that what the fit tests alone make of its parameters fails, not its form
   function carry_note(res, jres, ag) result(text)
      type(diagnose_result), intent(in) :: res, jres
      type(agreement_type), intent(in) :: ag   !< see agreement_of
      character(len=:), allocatable :: text, carried
      associate (e => res%effects(res%leading))
         text = 'with the held-out tests fitted too, '//jres%verdict
         if (jres%leading == 0) then
            if (.not. fit_structured(jres)) text = 'fitted to every test together, the model without '// &
               'an effect is at the noise level: the held-out gap it leaves may come from constants the '// &
               'fit tests alone leave loose'
            return
         end if
         associate (je => jres%effects(jres%leading))
            if (je%name /= e%name) return
            text = 'fitted to every test together, '//trim(e%name)//' removes '// &
                   real_str(100.0_dp*je%shrink_fit, 'f0.1')//' % of their structured gap (BIC '// &
                   real_str(je%dbic, 'f0.1')//')'//agreement_text(ag)
            ! What the leader made of the held-out gap from the fit tests alone
            if (e%held_fitted) then
               carried = 'its values fitted to the held-out tests meet '// &
                         real_str(100.0_dp*e%shrink_held, 'f0.1')//' % of their gap'
            else
               carried = 'its parameters carry '//real_str(100.0_dp*e%shrink_held, 'f0.1')// &
                         ' % of the held-out gap'
            end if
            if (ag%agrees) then
               text = text//': it explains every test, and the fit tests leave open what the held-out '// &
                      'tests need: with the constants they alone give it, '//carried
            else if (explains_resolved(je, jres)) then
               text = text//': it can explain every test, but with the constants the fit tests alone give '// &
                      'it, '//carried
            else
               text = text//': the held-out tests show more than it carries'
            end if
         end associate
      end associate
   end function carry_note

   !> How much of the held-out tests' gap (against their noise alone) the leader removes with
   !> every test fitted together (the joint stage jres), and whether the fit tests allow the
   !> constants of that fit: their deviance above that of the leader's refit on them alone
   !> against the 95 % point of chi-square in the parameters the tests share (the constants
   !> and the effect's global ones), the likelihood-ratio region of those parameters. Within
   !> it the fit tests cannot tell the joint constants from their own, and what the prediction
   !> left is what they leave open, not what the effect misses. It agrees where the same
   !> effect leads the joint stage and explains it with no other effect alike there
   !> (carry_note gives the leader's figures alone) and removes most of the held-out gap
   !> within that region.
   function agreement_of(res, jres) result(ag)
      type(diagnose_result), intent(in) :: res, jres
      type(agreement_type) :: ag
      real(dp) :: noise_only
      logical, allocatable :: fit(:)
      if (res%leading == 0 .or. jres%leading == 0) return
      associate (e => res%effects(res%leading), je => jres%effects(jres%leading))
         if (je%name /= e%name) return
         if (.not. (allocated(e%per_test_after) .and. allocated(je%per_test_after) .and. allocated(res%npts))) return
         if (.not. (allocated(res%held) .and. allocated(res%c))) return
         if (size(je%per_test_after) /= size(res%held) .or. size(e%per_test_after) /= size(res%held)) return
         if (res%gap_held_noise <= 0.0_dp) return
         fit = .not. res%held
         noise_only = res%noise_held - res%pred_held
         ag%share = 1.0_dp - max(sum(je%per_test_after, res%held) - noise_only, 0.0_dp)/res%gap_held_noise
         ag%dev = deviance_change(pack(res%npts, fit), pack(e%per_test_after, fit), pack(je%per_test_after, fit))
         ag%nshared = size(res%c)
         if (allocated(e%p_test)) ag%nshared = ag%nshared + count(e%p_test == 0)
         ag%crit = chi2_isf(0.05_dp, real(ag%nshared, dp))
         ag%measured = .true.
         ag%agrees = ag%share >= most .and. ag%dev <= ag%crit .and. explains_resolved(je, jres)
         if (allocated(jres%alike)) ag%agrees = ag%agrees .and. size(jres%alike) <= 1
      end associate
   end function agreement_of

   !> agreement_of as a clause ('' where not measured)
   pure function agreement_text(ag) result(text)
      type(agreement_type), intent(in) :: ag
      character(len=:), allocatable :: text
      logical :: within
      text = ''
      if (.not. ag%measured) return
      within = ag%dev <= ag%crit
      text = ' and '//real_str(100.0_dp*ag%share, 'f0.1')//' % of the held-out tests'' gap against their noise, '// &
             'at constants the fit tests '//trim(merge('allow       ', 'do not allow', within))// &
             ' (their deviance '//trim(merge('up  ', 'down', ag%dev >= 0.0_dp))//' '//real_str(abs(ag%dev), 'f0.1')// &
             ' from their own fit, '//trim(merge('within', 'beyond', within))//' the '// &
             real_str(ag%crit, 'f0.1')//' of a 95 % region of the '//str(ag%nshared)//' parameters the tests share)'
   end function agreement_text

   !> Why a leader that rests on a fit of the held-out tests (see held_fit_only) gave way to
   !> the diagnosis with every test fitted, as a clause
   function held_fit_note(res) result(text)
      type(diagnose_result), intent(in) :: res
      character(len=:), allocatable :: text
      associate (e => res%effects(res%leading))
         text = 'on the fit tests alone '//trim(e%name)//' led by BIC '//real_str(e%dbic, 'f0.1')
         if (fit_structured(res)) then
            text = text//', removing '//real_str(100.0_dp*e%shrink_fit, 'f0.1')//' % of their structured gap'
         else
            text = text//' with their structured gap below its floor'
         end if
         text = text//', and met the held-out tests only by its parameters fitted to them, not predicted'
      end associate
   end function held_fit_note

   !> Why a leader that an effect of open form beat on the fit tests (see form_beats_leader)
   !> gave way to the diagnosis with every test fitted, as a clause
   function beaten_note(res) result(text)
      type(diagnose_result), intent(in) :: res
      character(len=:), allocatable :: text
      associate (e => res%effects(res%leading), o => res%effects(form_beats_leader(res)))
         text = 'on the fit tests alone '//trim(e%name)//' led, removing '// &
                real_str(100.0_dp*e%shrink_fit, 'f0.1')//' % of their structured gap'
         if (e%shrink_fit >= most .and. held_rest_open(res)) &
            text = text//' and '//real_str(100.0_dp*e%shrink_held, 'f0.1')//' % of the held-out '// &
                   'tests'', short of their floor'
         text = text//', while '//trim(o%name)//' fitted them better by BIC '// &
                real_str(o%dbic - e%dbic, 'f0.1')//' but did not carry to the held-out tests'
      end associate
   end function beaten_note

   !> An effect's chi-square at the low end of its range and the power against it, as two
   !> table cells ('-' where not computed)
   function power_cells(lambda, power) result(text)
      real(dp), intent(in) :: lambda, power
      character(len=:), allocatable :: text
      if (power < 0.0_dp) then
         text = '- | -'
      else
         text = real_str(lambda, 'es9.2')//' | '//power_text(power)
      end if
   end function power_cells

   !> A power with two decimals cut, not rounded (0.949 is short of 0.95), so that the table
   !> and the verdict print the same figure
   pure function power_text(power) result(text)
      real(dp), intent(in) :: power
      character(len=:), allocatable :: text
      text = real_str(real(floor(100.0_dp*power), dp)/100.0_dp, 'f0.2')
   end function power_text

   !> The effects the tests could miss at the low end of their ranges (the rule's power there
   !> below 0.95), as a clause of a verdict ('' when there are none): for each, that power,
   !> how much of it the rule finds with power 0.95, and the test that would find that much
   function missed_note(names, power, hidden, subject) result(text)
      character(len=*), intent(in) :: names(:)
      real(dp), intent(in) :: power(:)
      type(hidden_effect), intent(in) :: hidden(:)
      !> the tests the power is of ('the fit tests alone', 'this test alone')
      character(len=*), intent(in) :: subject
      character(len=:), allocatable :: text
      integer :: j
      text = ''
      do j = 1, size(names)
         if (power(j) < 0.0_dp .or. power(j) >= 0.95_dp) cycle
         if (len(text) > 0) text = text//', '
         text = text//trim(names(j))//' (power '//power_text(power(j))//' there'
         associate (h => hidden(j))
            if (h%times > 0.0_dp .and. h%beyond) then
               text = text//'; not found with power 0.95 within its physical limit'
            else if (h%times > 0.0_dp) then
               text = text//'; found with power 0.95 from '//real_str(h%times, 'f0.1')//' times it'
               if (len_trim(h%magnitude) > 0) text = text//', '//trim(h%magnitude)
               ! (a test named only where it finds it more often than these tests do)
               if (len_trim(h%test) > 0 .and. h%power > power(j)) text = text//', which a '// &
                  trim(h%test)//' would find with power '//power_text(h%power)
            end if
         end associate
         text = text//')'
      end do
      if (len(text) > 0) text = '; at the low end of their ranges '//subject//' could miss: '//text
   end function missed_note

   !> The effects the fitted tests of res could miss (missed_note): the fit tests alone, or
   !> every test when none is held out (the stage with every test fitted)
   function stage_missed_note(res) result(text)
      type(diagnose_result), intent(in) :: res
      character(len=:), allocatable :: text
      ! (copied: a component of an array of derived type is not contiguous)
      character(len=16), allocatable :: names(:)
      real(dp), allocatable :: power(:)
      type(hidden_effect), allocatable :: hidden(:)
      names = res%effects%name
      power = res%effects%power_low
      hidden = res%effects%hidden
      text = missed_note(names, power, hidden, trim(merge('the fit tests alone      ', 'the tests fitted together', &
                                                          any(res%held))))
   end function stage_missed_note

   !> The verdict when no effect is confirmed
   subroutine no_effect(res)
      type(diagnose_result), intent(inout) :: res
      integer :: j
      integer, allocatable :: top(:)
      character(len=:), allocatable :: where
      if (.not. any(res%regions%structured) .or. (.not. fit_structured(res) .and. held_quiet(res))) then
         res%verdict = 'no significant effect: the residual is at the noise level'
         ! Runs in a region while both sets' gaps lie below their floors: the floors decide
         if (any(res%regions%structured)) res%verdict = 'no significant effect: the structured gap '// &
            'of both sets lies below its floor (the noise and, for the held-out tests, the fitted '// &
            'constants'' own uncertainty): whatever effect there is lies below what these tests '// &
            'detect'//serration_note(res)
         do j = 1, size(res%effects)
            if (res%effects(j)%significant) res%verdict = res%verdict//'; '// &
               trim(res%effects(j)%name)//' lowers BIC, but '//why_not(res%effects(j), res)
         end do
         res%verdict = res%verdict//suggested_note(res)//stage_missed_note(res)
         return
      end if
      where = ''
      top = top_regions(res%regions, size(res%regions))
      top = pack(top, res%regions(top)%structured .and. res%regions(top)%label /= 'serrated flow')
      do j = 1, min(3, size(top))
         if (j > 1) where = where//'; '
         where = where//trim(res%regions(top(j))%test)//' '//trim(res%regions(top(j))%label)
      end do
      res%verdict = 'no catalogue effect is confirmed'//serration_note(res)
      if (len(where) > 0) res%verdict = res%verdict//'; the structured residual lies in: '//where
      do j = 1, size(res%effects)
         if (res%effects(j)%significant) res%verdict = res%verdict//'; '// &
            trim(res%effects(j)%name)//' lowers BIC, but '//why_not(res%effects(j), res)
      end do
      res%verdict = res%verdict//suggested_note(res)
   end subroutine no_effect

   !> In a verdict of no effect, the refit that lowers BIC most, by at least hint_margin but
   !> less than bic_margin, as a clause ('' if none does): the wording follows the evidence,
   !> which is then strong, not none (a drift at the low end, fitted to every test at 6.4e-8
   !> [4.0e-8, 8.8e-8] 1/s against the injected 8.3e-8, lowered BIC by 8.3 and AIC by 26.2
   !> under a plain "no significant effect"; refits on clean data lowered it by up to 5.5)
   function suggested_note(res) result(text)
      type(diagnose_result), intent(in) :: res
      character(len=:), allocatable :: text
      logical, allocatable :: weak(:)
      integer :: k
      text = ''
      weak = res%effects%refitted .and. .not. res%effects%significant .and. res%effects%dbic <= -hint_margin
      if (.not. any(weak)) return
      k = minloc(res%effects%dbic, 1, mask=weak)
      associate (e => res%effects(k))
         text = '; '//trim(e%name)//' lowers BIC by '//real_str(-e%dbic, 'f0.1')//' (AIC by '// &
                real_str(-e%daic, 'f0.1')//'), short of the '//str(nint(bic_margin))// &
                ' a finding needs: a hint, not a finding, that more or longer tests would settle'
      end associate
   end function suggested_note

   !> Why a significant effect is not confirmed, briefly
   function why_not(e, res) result(text)
      type(effect_outcome), intent(in) :: e
      type(diagnose_result), intent(in) :: res
      character(len=:), allocatable :: text
      if (.not. e%plausible) then
         ! (the largest fitted value; plausibility asks its interval too: see beyond_limit)
         text = 'its fitted '//trim(e%worst_what)//' reaches '//real_str(e%worst, 'f0.1')//' x its physical limit'
      else if (.not. e%resolved) then
         text = 'its delay is below the sampling interval ('//real_str(res%dt_sample, 'g0.3')// &
                ' s) and it does not remove most of the gap'
      else if (e%carried_by_constants) then
         text = 'its refit''s constants carry the held-out tests without it ('// &
                real_str(100.0_dp*e%shrink_held_constants, 'f0.1')//' % of their gap, with it '// &
                real_str(100.0_dp*e%shrink_held, 'f0.1')//' %; what they leave lies below its floor): '// &
                'the fit tests leave the constants loose'
      else
         text = 'it does not carry to the held-out tests'
      end if
   end function why_not

   !> Names of the tests in mask, comma-separated
   function test_list(res, mask) result(text)
      type(diagnose_result), intent(in) :: res
      logical, intent(in) :: mask(:)
      character(len=:), allocatable :: text
      integer :: i
      text = ''
      do i = 1, size(mask)
         if (.not. mask(i)) cycle
         if (len(text) > 0) text = text//', '
         text = text//trim(res%names(i))
         if (allocated(res%held)) then
            if (i <= size(res%held)) then
               if (res%held(i)) text = text//' (held out)'
            end if
         end if
      end do
   end function test_list

   !> Regions other than whole tests, by structured gap, largest first; at most nmax
   pure function top_regions(regs, nmax) result(idx)
      type(region_stat), intent(in) :: regs(:)
      integer, intent(in) :: nmax
      integer, allocatable :: idx(:)
      idx = order_of(-regs%gap)
      idx = pack(idx, regs(idx)%label /= 'whole test')
      idx = idx(1:min(nmax, size(idx)))
   end function top_regions

   !> One refit's verdict, in words scaled with the evidence
   function verdict_of(e, res) result(text)
      type(effect_outcome), intent(in) :: e
      type(diagnose_result), intent(in) :: res
      character(len=:), allocatable :: text, how
      integer :: i, j
      ! What the confirmation rests on: a prediction of the held-out tests, values of a per-test
      ! effect fitted to them, or (no test held out: every test fitted together) a fit
      how = 'confirmed'
      if (allocated(res%held)) then
         if (.not. any(res%held)) then
            how = 'fitted to every test'
         else if (e%held_fitted) then
            how = 'met the held-out tests by its values fitted to them'
         end if
      end if
      if (e%confirmed .and. explains_resolved(e, res)) then
         text = how//': explains the gap'
      else if (e%confirmed) then
         text = how//': partly explains the gap'
      else if (e%significant) then
         text = 'lowers BIC, but '//why_not(e, res)
         if (.not. e%plausible) text = text//': stands in for something else'
         if (e%plausible .and. .not. e%resolved) text = text//': not a finding'
      else
         text = 'not significant'
      end if
      j = 0
      do i = 1, size(res%effects)
         if (res%effects(i)%k == e%k) j = i
      end do
      if (e%confirmed .and. allocated(res%alike) .and. res%leading > 0) then
         if (j == res%leading .and. size(res%alike) > 1) then
            if (len(lead_peers(res)) == 0) then
               text = text//', leads as the simplest of those that explain it equally well'
            else
               text = text//', leads by BIC among the simplest of those that explain it alike'
            end if
         else if (any(res%alike == j) .and. j /= res%leading) then
            if (abs(e%dbic - res%effects(res%leading)%dbic) < bic_margin) then
               text = text//', as well as '//trim(res%effects(res%leading)%name)//': the tests cannot tell them apart'
            else
               if (res%effects(res%leading)%dbic < e%dbic) then
                  text = text//', to the noise level as '//trim(res%effects(res%leading)%name)//' does, '// &
                         'which BIC prefers'
               else
                  text = text//', to the noise level as '//trim(res%effects(res%leading)%name)//' does, '// &
                         'which is simpler'
               end if
            end if
         else if (j /= res%leading) then
            text = text//', but '//trim(res%effects(res%leading)%name)//' is better by BIC'
         end if
      end if
      if (allocated(e%worse)) then
         if (any(e%worse)) text = text//'; makes '//test_list(res, e%worse)//' worse'
      end if
   end function verdict_of

   !> Whether the shares of the structured gaps an effect removes (on the fit tests, and on the
   !> held-out tests where they have one) all lie below little: no explanation, though BIC
   !> may fall (a drift that removed 7 % of the gap of clean data with correlated noise)
   pure logical function little_share(e, res)
      type(effect_outcome), intent(in) :: e
      type(diagnose_result), intent(in) :: res
      real(dp) :: share
      share = 0.0_dp
      if (fit_structured(res)) share = e%shrink_fit
      if (allocated(res%held)) then
         if (any(res%held) .and. .not. held_quiet(res)) share = max(share, e%shrink_held)
      end if
      little_share = (fit_structured(res) .or. share > 0.0_dp) .and. share < little
   end function little_share

   !> x/(1 + |x|): increasing, in (-1, 1)
   elemental real(dp) function squash(x)
      real(dp), intent(in) :: x
      squash = x/(1.0_dp + abs(x))
   end function squash

   !> What the end points of the refit that the fit tests cannot tell apart carry of the
   !> held-out gap, where they leave the prediction open (prediction_open; '' otherwise)
   function alike_note(e) result(text)
      type(effect_outcome), intent(in) :: e
      character(len=:), allocatable :: text
      text = ''
      if (.not. prediction_open(e)) return
      text = ' (the responses of '//str(e%n_alike + 1)//' end points of its refit that the fit '// &
             'tests cannot tell apart, BIC within '//str(nint(bic_margin))//', weighted by them; '// &
             'one by one they carry '//real_str(100.0_dp*e%shrink_alike_lo, 'f0.1')//' to '// &
             real_str(100.0_dp*e%shrink_alike_hi, 'f0.1')//' %: they leave the held-out prediction open)'
   end function alike_note
end module usharp_diagnose_verdict
