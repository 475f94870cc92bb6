!> The report of a diagnosis: Markdown (also what `diagnose` prints), the CSV tables
!> (regions, effects, every point's residual) and the gnuplot plots
module usharp_diagnose_report
   use usharp_kinds, only: dp
   use usharp_error, only: error_type
   use usharp_strings, only: str, real_str, gnuplot_string, csv_field, report_line_len, add_line, &
                             interval_end
   use usharp_process, only: run_process, process_result, proc_exited
   use usharp_regions, only: class_names
   use usharp_filesys, only: join_path, make_dir, remove_file, rename_file
   use usharp_overwrite, only: drawn_line
   use usharp_output, only: write_lines
   use usharp_diagnose_options, only: diagnose_options, bic_margin, gap_z, corr_lag, correlated_ratio, rival_share
   use usharp_diagnose_types, only: diagnose_result, effect_outcome, delay_precision, form_beats_leader, &
                                    joint_reason, joint_partial, joint_bic_only, joint_held_fit, joint_not_carried, &
                                    joint_form_beats, joint_loose, fit_effect_not_carried, unit_text, &
                                    fit_structured, most, bound_list, per_test_ref, joint_decides, held_quiet, side_word, &
                                    rate_at_end, separation_type, prediction_open
   use usharp_diagnose_verdict, only: verdict_of, top_regions, power_cells, carried_clause
   use usharp_diagnose_numerics, only: held_rate
   use usharp_effects, only: effect_info, effect_catalogue, n_effects, param_per_test
   implicit none
   private

   public :: diagnose_report, write_report, report_names, report_marks

   !> The files write_report writes in its folder, and how the first line of each begins
   !> when it wrote it (the plots: by their hashes, which plots.gp records; see drawn_line)
   character(len=*), parameter :: report_names(8) = [character(len=13) :: 'report.md', &
      'steps.csv', 'regions.csv', 'effects.csv', 'residuals.csv', 'plots.gp', 'residuals.png', 'fit.png']
   character(len=*), parameter :: report_marks(8) = [character(len=29) :: '# usharp diagnose', &
      'step,simulations,', 'test,region,points,', 'stage,rank,effect,parameters,', 'test,held_out,t_s,', &
      "set datafile separator ','", '@plots.gp', '@plots.gp']

contains

   !> The report in Markdown (also what `diagnose` prints)
   function diagnose_report(res, opts) result(lines)
      type(diagnose_result), intent(in) :: res
      type(diagnose_options), intent(in) :: opts
      character(len=report_line_len), allocatable :: lines(:)
      allocate (lines(0))
      call add_line(lines, '# usharp diagnose')
      call add_line(lines, '')
      call add_line(lines, '**Verdict:** '//res%verdict)
      call add_line(lines, '')
      call where_section(lines, res)
      call which_section(lines, res, opts)
      call shrink_section(lines, res, opts)
      call separate_section(lines, res)
      if (allocated(res%joint)) call joint_section(lines, res, opts)
      call own_section(lines, res)
      call add_line(lines, '')
      call add_line(lines, str(res%nevals)//' simulations of the test set.')
      call steps_list(lines, res)
   end function diagnose_report

   !> The simulations of each step that ran any, one line each
   subroutine steps_list(lines, res)
      character(len=report_line_len), allocatable, intent(inout) :: lines(:)
      type(diagnose_result), intent(in) :: res
      integer :: j
      if (.not. allocated(res%steps)) return
      if (.not. any(res%steps%nevals > 0)) return
      call add_line(lines, '')
      call add_line(lines, 'Simulations by step:')
      call add_line(lines, '')
      do j = 1, size(res%steps)
         if (res%steps(j)%nevals > 0) call add_line(lines, '- '//trim(res%steps(j)%name)//': '//str(res%steps(j)%nevals))
      end do
   end subroutine steps_list

   !> The log of a diagnosis: each step's simulations, elapsed and processor time (s)
   function diagnose_log(res) result(lines)
      type(diagnose_result), intent(in) :: res
      character(len=report_line_len), allocatable :: lines(:)
      integer :: j
      allocate (lines(0))
      call add_line(lines, 'step,simulations,wall_s,cpu_s')
      if (.not. allocated(res%steps)) return
      do j = 1, size(res%steps)
         associate (st => res%steps(j))
            call add_line(lines, csv_field(trim(st%name))//','//str(st%nevals)//','//real_str(st%wall, 'f0.2')//','// &
                     real_str(st%cpu, 'f0.2'))
         end associate
      end do
      call add_line(lines, 'total,'//str(sum(res%steps%nevals))//','//real_str(sum(res%steps%wall), 'f0.2')//','// &
               real_str(sum(res%steps%cpu), 'f0.2'))
   end function diagnose_log

   !> Section 1: the baseline per test, the floors, the regions ranked by structured gap
   subroutine where_section(lines, res)
      character(len=report_line_len), allocatable, intent(inout) :: lines(:)
      type(diagnose_result), intent(in) :: res
      integer, allocatable :: order(:)
      integer :: i, k
      character(len=:), allocatable :: starts
      call add_line(lines, '## 1. Where the gap lies')
      call add_line(lines, '')
      if (allocated(res%rebased_by)) then
         starts = 'from the constants of the '//res%rebased_by//' refit'
      else
         starts = 'best of '//str(res%baseline_starts)//' start'//trim(merge('s', ' ', res%baseline_starts > 1))
      end if
      call add_line(lines, 'Baseline: the model without any effect fitted to the fit tests (objective '// &
               real_str(res%f0, 'es11.4')//', '//str(res%m)//' residuals, '//starts//', its search '// &
               str(res%baseline_iterations)//' iterations); held-out tests predicted.')
      if (allocated(res%rebased_by)) call add_line(lines, 'The baseline was fitted again from the '// &
         'constants of the '//res%rebased_by//' refit: without their effect they fit the fit tests '// &
         'better than the earlier baseline (objective '//real_str(res%f0_left, 'es11.4')//'), which '// &
         'was therefore not the optimum of the constants; every step below starts from this one (which '// &
         'refits ran against the earlier baseline depended on the held-out tests'' prediction too).')
      if (.not. res%baseline_converged) call add_line(lines, '**Flag:** the baseline fit had not '// &
         'converged when its iterations or evaluations ran out; every effect below is judged against it, and '// &
         'a refit may owe part of its fall to the constants alone.')
      if (allocated(res%c_bound)) then
         if (any(res%c_bound /= 0)) call add_line(lines, '**Flag:** the baseline fit ran away: '// &
            bound_list(res%cnames, res%c, res%c_bound)//' at a search bound of &fit; '// &
            'its figures describe a fit that did not converge inside the bounds.')
      end if
      call add_line(lines, 'Noise: estimated from each test''s residual at the baseline (second differences, robust: the')
      call add_line(lines, 'model takes out the response''s own curvature); the objective it explains is set against the')
      call add_line(lines, 'residual. Structured gap = objective - noise part. Correlation: the noise sd from second')
      call add_line(lines, 'differences '//str(corr_lag)//' samples apart over that from neighbours, 1 for '// &
                    'independent noise; above '//real_str(correlated_ratio, 'f0.1')//' the')
      call add_line(lines, 'noise is correlated from sample to sample, its sd larger than the estimate, and the floors and')
      call add_line(lines, 'BIC below, which assume independent noise, overstate the evidence.')
      call add_line(lines, '')
      call add_line(lines, '| test | role | response | noise sd | % of peak | correlation | objective | noise part | '// &
                    'structured gap |')
      call add_line(lines, '|---|---|---|---|---|---|---|---|---|')
      do i = 1, size(res%names)
         call add_line(lines, '| '//trim(res%names(i))//' | '//trim(merge('held out', 'fit     ', res%held(i)))// &
            ' | '//trim(res%unit(i))//' | '//real_str(res%noise(i), 'es10.3')//' | '// &
            real_str(100.0_dp*res%noise(i)/res%peak(i), 'f0.2')//' | '//corr_cell(res, i)//' | '// &
            real_str(res%per_test0(i), 'es10.3')//' | '//real_str(region_noise(res, i), 'es10.3')//' | '// &
            real_str(max(res%per_test0(i) - region_noise(res, i), 0.0_dp), 'es10.3')//' |')
      end do
      call add_line(lines, '')
      if (res%global .and. res%f0_global < res%f0 .and. allocated(res%per_test_global)) then
         starts = ''
         do i = 1, size(res%names)
            if (res%held(i)) cycle
            if (len(starts) > 0) starts = starts//', '
            starts = starts//trim(res%names(i))//' '//real_str(res%per_test_global(i), 'es10.3')
         end do
         call add_line(lines, 'The Latin-hypercube starts of section 2 found a lower baseline of the fit tests '// &
            '(objective '//real_str(res%f0_global, 'es11.4')//', '//real_str(res%f0 - res%f0_global, 'es9.2')// &
            ' below the first'//'; per test: '//starts//'): the "before" '// &
            'of section 2 and its shares are against it; the held-out tests'' figures stay this table''s '// &
            '(the prediction of the first baseline).')
      end if
      if (allocated(res%data_notes)) then
         do i = 1, size(res%data_notes)
            if (len_trim(res%data_notes(i)) > 0) call add_line(lines, 'Data of '//trim(res%names(i))// &
               ': '//trim(res%data_notes(i))//'.')
         end do
      end if
      call add_line(lines, 'A set of tests has a structured gap only above '//str(nint(gap_z))// &
               ' standard errors of the gap noise alone leaves (the scatter of the noise')
      call add_line(lines, 'estimate and of the objective): fit tests '//real_str(res%gap_fit, 'es10.3')//' against '// &
               real_str(res%floor_fit, 'es10.3')//', held-out tests '//real_str(res%gap_held, 'es10.3')// &
               ' against '//real_str(res%floor_held, 'es10.3')//'.')
      if (any(res%held)) call add_line(lines, 'The table''s noise part is the noise alone. The held-out '// &
         'tests'' gap here is set against a noise part that also holds '//real_str(res%pred_held, 'es10.3')// &
         ', what the fitted constants'' own uncertainty explains (their covariance from the fit tests'' '// &
         'noise, carried linearly to the held-out tests), and their floor its scatter.')
      call add_line(lines, '')
      call add_line(lines, 'Regions ranked by structured gap (share: of the objective of the test set the region')
      call add_line(lines, 'belongs to; bias = mean of data - model; runs z < -3 with more residual than noise: structured):')
      call add_line(lines, '')
      call add_line(lines, '| rank | test | region | points | share % | RMS | bias | runs z | mean square residual/noise | |')
      call add_line(lines, '|---|---|---|---|---|---|---|---|---|---|')
      order = top_regions(res%regions, 15)
      do k = 1, size(order)
         i = order(k)
         call add_line(lines, '| '//str(k)//' | '//trim(res%regions(i)%test)//' | '//trim(res%regions(i)%label)// &
            ' | '//str(res%regions(i)%n)//' | '//real_str(100.0_dp*res%regions(i)%ssr/set_total(res, i), 'f0.1')// &
            ' | '//real_str(res%regions(i)%rms, 'es9.2')//' | '//real_str(res%regions(i)%bias, 'es9.2')// &
            ' | '//real_str(res%regions(i)%z, 'f0.1')//' | '//ratio_text(res%regions(i)%ratio)//' | '// &
            trim(merge('structured', 'noise     ', res%regions(i)%structured))//' |')
      end do
      call add_line(lines, '')
   end subroutine where_section

   !> Section 2: screening and refits
   subroutine which_section(lines, res, opts, heading)
      character(len=report_line_len), allocatable, intent(inout) :: lines(:)
      type(diagnose_result), intent(in) :: res
      type(diagnose_options), intent(in) :: opts
      character(len=*), intent(in), optional :: heading  !< instead of section 2's
      integer :: j
      real(dp) :: f_ref
      type(effect_info) :: cat(n_effects)
      cat = effect_catalogue(1.0_dp)
      if (present(heading)) then
         call add_line(lines, heading)
      else
         call add_line(lines, '## 2. Which unmodelled effect explains it')
      end if
      call add_line(lines, '')
      call add_line(lines, 'Screening (score test at the baseline): predicted fall of the objective from a Gauss-Newton')
      call add_line(lines, 'step in the effect''s parameters with the constants re-optimised; predicted BIC change.')
      call add_line(lines, 'Power: of the significance rule (dBIC < -'//real_str(bic_margin, 'f0.0')//') against the '// &
         'effect at the low end of its realistic range on '//trim(merge('the fit tests', 'every test   ', &
         any(res%held)))//', from the expected chi-square of '// &
         'its signal there beyond what the constants take up, at the baseline''s residual (linear in the '// &
         'effect; a per-test effect at that magnitude in every '//trim(merge('fit test', 'test    ', any(res%held)))// &
         ' and in each alone, the least; '// &
         'of two parameters the weaker).')
      call add_line(lines, '')
      call add_line(lines, '| rank | effect | parameters | predicted fall | % of objective | predicted dBIC | '// &
         'low end | chi-square there | power |')
      call add_line(lines, '|---|---|---|---|---|---|---|---|---|')
      do j = 1, size(res%effects)
         associate (e => res%effects(j))
            call add_line(lines, '| '//str(j)//' | '//trim(e%name)//' | '//str(e%q)//' | '// &
               real_str(e%pred_drop, 'es10.3')//' | '//real_str(100.0_dp*e%pred_drop/res%f0, 'f0.1')// &
               ' | '//real_str(e%pred_dbic, 'f0.1')//' | '//trim(cat(e%k)%low_what)//' | '// &
               power_cells(e%lambda_low, e%power_low)//' |')
         end associate
      end do
      if (allocated(opts%inert)) then
         if (size(opts%inert) > 0) call add_line(lines, '(not considered, as they do not act on this '// &
            'model: '//inert_list()//')')
      end if
      call add_line(lines, '')
      call add_line(lines, 'Refits of the leading '//str(count(res%effects%refitted))//' (constants and the '// &
               'effect''s parameters; dAIC, dBIC < 0: better; significant: dBIC < -'// &
               real_str(bic_margin, 'f0.0')//'; those that lower BIC ran again from the baseline''s '// &
               'constants, the best other refit''s and Latin-hypercube points, the lowest end kept):')
      if (count(res%effects%refitted) > opts%n_refit) call add_line(lines, '(beyond the leading '// &
         str(opts%n_refit)//': those the screening could not tell from them (predicted BIC within 10 % of the last, '// &
         'or a predicted fall at least '//str(nint(100.0_dp*rival_share))//' % of the largest); the lower-ranked '// &
         'where none of the leading was confirmed or took the fit tests'' structured gap to its floor, '// &
         'or where only the held-out tests had one; '// &
         'those simpler than a leader with parameters per test that the screening found significant or '// &
         'whose predicted fall is at least '//str(nint(100.0_dp*rival_share))//' % of the leader''s)')
      if (res%global) call add_line(lines, '(no significant local refit brought the fit tests'' structured gap '// &
         'down to the noise level, '//real_str(res%floor_fit, 'es9.2')//': the baseline and the refits also ran from '// &
         str(size(res%x_global, 2))//' Latin-hypercube starts of the constants; baseline from them and from '// &
         'each refit''s constants '// &
         real_str(res%f0_global, 'es10.3')//', the lower of the two is the reference of dAIC, dBIC and the gap shares)')
      call add_line(lines, '')
      ! Before: the reference of dAIC and dBIC, the lower baseline
      f_ref = res%f0
      if (res%global) f_ref = min(res%f0, res%f0_global)
      call add_line(lines, '| effect | objective before | after | dAIC | dBIC | gap removed, fit % | held-out % | verdict |')
      call add_line(lines, '|---|---|---|---|---|---|---|---|')
      do j = 1, size(res%effects)
         associate (e => res%effects(j))
            if (.not. e%refitted) cycle
            call add_line(lines, '| '//trim(e%name)//' | '//real_str(f_ref, 'es10.3')//' | '// &
               real_str(e%f_after, 'es10.3')//' | '//real_str(e%daic, 'f0.1')//' | '// &
               real_str(e%dbic, 'f0.1')//' | '//real_str(100.0_dp*e%shrink_fit, 'f0.1')//' | '// &
               held_share(e)//' | '//trim(verdict_of(e, res))//' |')
         end associate
      end do
      do j = 1, size(res%effects)
         if (res%effects(j)%refitted) call refit_details(lines, res, res%effects(j))
      end do
      call add_line(lines, '')
   contains
      !> The effects left out, each with why
      function inert_list() result(text)
         character(len=:), allocatable :: text
         integer :: i
         text = ''
         do i = 1, size(opts%inert)
            if (i > 1) text = text//'; '
            text = text//trim(cat(opts%inert(i))%name)//': '//trim(opts%inert_why(i))
         end do
      end function inert_list

      !> The held-out gap an effect removes, %; '-' when every test is fitted
      function held_share(e) result(text)
         type(effect_outcome), intent(in) :: e
         character(len=:), allocatable :: text
         text = '-'
         if (any(res%held)) text = real_str(100.0_dp*e%shrink_held, 'f0.1')
      end function held_share
   end subroutine which_section

   !> One refit: its fitted magnitude, the objective per test and the top regions before and after
   subroutine refit_details(lines, res, e)
      character(len=report_line_len), allocatable, intent(inout) :: lines(:)
      type(diagnose_result), intent(in) :: res
      type(effect_outcome), intent(in) :: e
      integer, allocatable :: order(:)
      integer :: i, k, g
      character(len=:), allocatable :: what, unit, why
      real(dp), allocatable :: before(:)
      logical :: lo_open, hi_open
      type(effect_info) :: cat(n_effects)
      order = top_regions(res%regions, 15)
      cat = effect_catalogue(1.0_dp)
      call add_line(lines, '')
      if (len_trim(e%worst_what) > 0) then
         what = ''
         if (allocated(e%worst_held_what)) then
            ! (the held-out tests' own values, fitted to them: reported, not judged)
            if (len(e%worst_held_what) > 0 .and. e%worst_held > e%worst) what = '; of a held-out test''s, '// &
               e%worst_held_what//', '//real_str(e%worst_held, 'f0.2')//' of it'
         end if
         call add_line(lines, '**'//trim(e%name)//'** fitted magnitude (95 % interval; largest against the '// &
            'physical limit of the catalogue: '//trim(e%worst_what)//', '//real_str(e%worst, 'f0.2')//' of it'// &
            what//'):')
      else
         call add_line(lines, '**'//trim(e%name)//'** fitted magnitude (95 % interval; no physical limit):')
      end if
      do k = 1, size(e%p)
         what = ''
         if (allocated(e%p_profiled)) then
            if (e%p_profiled(k)) what = ' (profile likelihood)'
         end if
         if (allocated(e%p_bound)) then
            if (k <= size(e%p_bound)) then
               if (e%p_bound(k) /= 0) then
                  what = what//': at its '//side_word(e%p_bound(k))//' search bound, which the data do not move it '// &
                     'from: its value is not determined and this interval does not hold'
               else if (any(e%p_bound /= 0)) then
                  ! (H3 at its bound leaves only H3/gamma3 determined, not gamma3)
                  what = what//': with '//bound_list(e%pname, side=e%p_bound)//' held at its bound, '// &
                     'so only as far as that holds'
               end if
            end if
         end if
         lo_open = .false.
         hi_open = .false.
         if (allocated(e%p_lo_open)) then
            lo_open = e%p_lo_open(k)
            hi_open = e%p_hi_open(k)
         end if
         unit = ''
         if (allocated(e%punit)) then
            if (k <= size(e%punit)) unit = unit_text(e%punit(k), res%stress_unit)
         end if
         call add_line(lines, '- '//trim(e%pname(k))//' = '//real_str(e%p(k), 'es11.4')//' ['// &
            interval_end(e%p_lo(k), lo_open, 'es11.4')//', '//interval_end(e%p_hi(k), hi_open, 'es11.4')// &
            ']'//unit//what)
      end do
      ! The constants it ends at, so that what follows from them (a separating test's
      ! responses) can be checked by a simulation of the user's
      if (allocated(e%c) .and. allocated(res%cnames)) then
         if (size(e%c) == size(res%cnames)) then
            what = '- constants of the refit:'
            do k = 1, size(e%c)
               what = what//trim(merge(' ', ',', k == 1))//' '//trim(res%cnames(k))//' = '//real_str(e%c(k), 'es11.4')
            end do
            call add_line(lines, what)
         end if
      end if
      ! What an initial drag offset adds to, or a specimen's factor scales
      if (e%drag0 > 0.0_dp .and. any(e%name == [character(len=8) :: 'initial', 'scatter'])) &
         call add_line(lines, '- the initial drag stress at those constants: D0 = '//real_str(e%drag0, 'es11.4')// &
            ' '//trim(res%stress_unit)//trim(merge(' (dD0 adds to it)  ', ' (dD0/D0 scales it)', e%name == 'initial')))
      if (e%held .and. allocated(e%p_all)) then
         k = held_rate(cat(e%k))
         if (e%rate_why == rate_at_end) then
            why = 'it ran to the end of its search box, where its interval ['// &
                  real_str(e%rate_lo, 'es11.4')//', '//real_str(e%rate_hi, 'es11.4')//'] does not hold,'
         else
            why = 'its interval ['//real_str(e%rate_lo, 'es11.4')//', '//real_str(e%rate_hi, 'es11.4')// &
                  '] spans zero or is open'
         end if
         if (k > 0) call add_line(lines, '- '//trim(cat(e%k)%pname(k))//' held at '// &
            real_str(e%p_all(k), 'es11.4')//' (the best of its screening starts'' rates): fitted free, '// &
            why//' and '//trim(e%worst_what)//' ran beyond its limit')
      end if
      ! The held-out tests' own values of a per-test effect (fitted to each with the constants
      ! fixed)
      associate (info => cat(e%k))
         if (allocated(e%p_all) .and. info%sharing == param_per_test) then
            do g = 1, info%nparam
               do i = 1, size(res%names)
                  ! (p_acts is p_all's companion: the same size)
                  if (allocated(e%p_acts) .and. (g - 1)*size(res%names) + i <= size(e%p_all)) then
                     if (.not. e%p_acts((g - 1)*size(res%names) + i)) cycle
                  end if
                  if (res%held(i) .and. (g - 1)*size(res%names) + i <= size(e%p_all)) &
                     call add_line(lines, '- '//trim(info%pname(g))//' '//trim(res%names(i))// &
                        ' (held out, fitted to it with the constants fixed) = '// &
                        real_str(e%p_all((g - 1)*size(res%names) + i), 'es11.4')// &
                        unit_text(info%punit(g), res%stress_unit))
               end do
            end do
         end if
      end associate
      if (.not. e%resolved .and. e%significant) call add_line(lines, '- the delay is below the sampling '// &
         'interval of the fit tests, '//real_str(res%dt_sample, 'g0.3')//' s: a finding only when it '// &
         'removes most of the structured gap on both sets, or when the data measure it (its 95 % '// &
         'interval within '//real_str(100.0_dp*delay_precision, 'f0.0')//' % of it'// &
         trim(merge(': so here ', ': not here', e%measured))//') and it removes most of the fit tests'' gap')
      if (allocated(e%shown_on) .and. e%dbic < e%dbic_all) call add_line(lines, '- its BIC counts the '// &
         'parameters of the tests that show it, '//e%shown_on//' ('//str(e%q_bic)//' of '//str(e%q)// &
         '): the others'' values are within what the noise allows (Wald chi-square below ln N per '// &
         'parameter); with every test''s counted, dBIC '//real_str(e%dbic_all, 'f0.1'))
      if (allocated(e%c_bound)) then
         if (any(e%c_bound /= 0)) call add_line(lines, '- **flag:** the refit ran away: '// &
            bound_list(res%cnames, e%c, e%c_bound)//' at a search bound of &fit')
      end if
      if (e%nstarts > 1) then
         what = ''
         if (e%nstarts_failed > 0) what = '; '//str(e%nstarts_failed)//' of them failed'
         call add_line(lines, '- refitted from '//str(e%nstarts)//' starts (its screening end '// &
            'point and further starts of the constants): objective '// &
            real_str(e%f_lo, 'es10.3')//' to '//real_str(e%f_hi, 'es10.3')//', the lowest is used'//what)
      end if
      if (e%f_unprofiled > 0.0_dp) call add_line(lines, '- refitted again from a lower point that its '// &
         'profile met: objective '//real_str(e%f_unprofiled, 'es10.3')//' -> '//real_str(e%f_after, 'es10.3')// &
         ', the figures from there')
      if (e%shrink_held_constants > -huge(1.0_dp) .and. any(res%held)) then
         ! (a negative share: they widen the gap)
         if (e%shrink_held_constants >= 0.0_dp) then
            what = 'remove '//real_str(100.0_dp*e%shrink_held_constants, 'f0.1')//' % of'
         else
            what = 'widen by '//real_str(-100.0_dp*e%shrink_held_constants, 'f0.1')//' %'
         end if
         call add_line(lines, '- its refit''s constants without the effect '//what//' the held-out gap'// &
            trim(merge(': the prediction is theirs, no evidence of the effect', &
                       '                                                     ', e%carried_by_constants)))
      end if
      if (e%n_alike > 0) call add_line(lines, '- end points of the refit that the fit tests cannot '// &
         'tell from the one used (BIC within '//real_str(bic_margin, 'f0.0')//'): '//str(e%n_alike)// &
         ' more; with them the held-out gap removed is '//real_str(100.0_dp*e%shrink_alike_lo, 'f0.1')// &
         ' to '//real_str(100.0_dp*e%shrink_alike_hi, 'f0.1')//' %; their responses weighted by '// &
         'the fit tests (exp(-deviance/2)) remove '//real_str(100.0_dp*e%shrink_held, 'f0.1')// &
         ' %, the prediction used (the one alone '//real_str(100.0_dp*e%shrink_held_point, 'f0.1')//' %)')
      ! (before: at the reference baseline, as "objective before")
      call add_line(lines, '- objective per test, before -> after:')
      before = per_test_ref(res)
      do k = 1, size(res%names)
         call add_line(lines, '  - '//trim(res%names(k))//trim(merge(' (held out)', '           ', res%held(k)))// &
            ': '//real_str(before(k), 'es10.3')//' -> '//real_str(e%per_test_after(k), 'es10.3'))
      end do
      call add_line(lines, '- top regions, structured gap before -> after:')
      do k = 1, min(5, size(order))
         i = order(k)
         call add_line(lines, '  - '//trim(res%regions(i)%test)//' '//trim(res%regions(i)%label)//': '// &
            real_str(res%regions(i)%gap, 'es10.3')//' -> '//real_str(e%regions(i)%gap, 'es10.3'))
      end do
   end subroutine refit_details

   !> Section 3: how far the leading effect closes the gap
   subroutine shrink_section(lines, res, opts)
      character(len=report_line_len), allocatable, intent(inout) :: lines(:)
      type(diagnose_result), intent(in) :: res
      type(diagnose_options), intent(in) :: opts
      call add_line(lines, '## 3. How far the gap shrinks')
      call add_line(lines, '')
      call add_line(lines, 'Structured gap at the baseline: fit tests '//real_str(res%gap_fit, 'es10.3')// &
               ', held-out tests '//real_str(res%gap_held, 'es10.3')//'.')
      if (res%leading > 0) then
         associate (e => res%effects(res%leading))
            call add_line(lines, 'With '//trim(e%name)//': fit tests '//real_str(100.0_dp*e%shrink_fit, 'f0.1')// &
               ' % removed, held-out tests '//real_str(100.0_dp*e%shrink_held, 'f0.1')//' % removed.')
         end associate
      else
         call add_line(lines, 'No effect is confirmed (significant, plausible, and removing at least '// &
            real_str(100.0_dp*opts%confirm_shrink, 'f0.0')//' % of the held-out structured gap, '// &
            'or opening none where there was none).')
      end if
      call skip_note(lines, res)
   end subroutine shrink_section

   !> Why a diagnosis with held-out tests did not go on to fit every test together (see
   !> joint_reason): a report that ends without that stage, where another deck's went on
   !> to it, says why
   subroutine skip_note(lines, res)
      character(len=report_line_len), allocatable, intent(inout) :: lines(:)
      type(diagnose_result), intent(in) :: res
      character(len=:), allocatable :: what
      if (allocated(res%joint) .or. .not. allocated(res%held)) return
      if (.not. any(res%held)) return
      if (res%leading > 0) then
         associate (e => res%effects(res%leading))
            if (held_quiet(res)) then
               ! (confirmed by leaving them at their noise: a share of a gap below its floor
               ! says nothing)
               what = 'leaves the held-out tests at their noise (structured gap '// &
                      real_str(e%held_gap, 'es10.3')//' against its floor '//real_str(res%floor_held, 'es10.3')//')'
            else
               what = 'removes '//real_str(100.0_dp*e%shrink_held, 'f0.1')//' % of the held-out tests'' '// &
                      'structured gap'
            end if
            call add_line(lines, 'Every test fitted together: not needed, the prediction decides: '// &
               trim(e%name)//', fitted to the fit tests alone, '//what// &
               trim(merge(' (its per-test parameters fitted to them, the rest carried over)', &
                          '                                                                ', &
                          e%held_fitted))//'.')
         end associate
      else
         call add_line(lines, 'Every test fitted together: not needed: the held-out tests show no structured '// &
            'gap against their noise alone ('//real_str(res%gap_held_noise, 'es10.3')//' against '// &
            real_str(res%floor_held_noise, 'es10.3')//'), so a fit of them has nothing to explain.')
      end if
   end subroutine skip_note

   !> Whether the report has section 4 (a test that would tell alike effects, or the
   !> leader's end points that leave its prediction open, apart)
   pure logical function has_separation(res)
      type(diagnose_result), intent(in) :: res
      has_separation = res%pin%best > 0
      if (allocated(res%seps)) has_separation = has_separation .or. size(res%seps) > 0
   end function has_separation

   !> Section 5, when the prediction could not decide (see joint_reason): the
   !> diagnosis of every test fitted together (jres)
   subroutine joint_section(lines, res, opts)
      character(len=report_line_len), allocatable, intent(inout) :: lines(:)
      !> the diagnosis of the fit tests, its joint stage in res%joint
      type(diagnose_result), intent(in) :: res
      type(diagnose_options), intent(in) :: opts
      character(len=:), allocatable :: what
      integer :: i
      associate (jres => res%joint)
      call add_line(lines, '')
      ! (section 4, the separating test, stands only where effects were alike)
      if (has_separation(res)) then
         call add_line(lines, '## 5. Every test fitted together')
      else
         call add_line(lines, '## 4. Every test fitted together')
      end if
      call add_line(lines, '')
      select case (joint_reason(res, .false.))
      case (joint_partial)
         if (prediction_open(res%effects(res%leading))) then
            call add_line(lines, trim(res%effects(res%leading)%name)//' leaves no structured gap on the fit '// &
               'tests, but they leave its prediction of the held-out tests open: the held-out tests fix '// &
               'the parameters it depends on.')
         else if (res%effects(res%leading)%held_fitted) then
            call add_line(lines, trim(res%effects(res%leading)%name)//' leaves no structured gap on the fit '// &
               'tests, but with its values of the held-out tests fitted to them and the fit tests'' constants '// &
               'carried over it meets only part of the held-out tests'' gap: either those constants fail '// &
               'there, or another effect adds to it.')
         else
            call add_line(lines, trim(res%effects(res%leading)%name)//' leaves no structured gap on the fit '// &
               'tests, but its prediction carries only part of the held-out tests'': either what the fit '// &
               'tests alone make of its parameters fails there, or another effect adds to it.')
         end if
      case (joint_bic_only)
         call add_line(lines, 'An effect leads on the fit tests by BIC alone (the held-out tests below their '// &
            'floor, and the fit tests'' structured gap below its floor too or mostly left): the held-out '// &
            'floor is too wide for the prediction to confirm it.')
      case (joint_held_fit)
         if (fit_structured(res)) then
            what = 'removes '//real_str(100.0_dp*res%effects(res%leading)%shrink_fit, 'f0.1')//' % of the '// &
                   'fit tests'' structured gap, under the '//real_str(100.0_dp*most, 'f0.0')//' % that '// &
                   'explains them,'
         else
            what = 'has no structured gap of the fit tests to explain'
         end if
         call add_line(lines, trim(res%effects(res%leading)%name)//' '//what//' and met '// &
            'the held-out tests only by its parameters fitted to them (an effect per test), not by a '// &
            'prediction: only every effect fitted to every test compares fairly.')
      case (joint_form_beats)
         call add_line(lines, trim(res%effects(form_beats_leader(res))%name)//' fits the fit tests better than '// &
            'the leader '//trim(res%effects(res%leading)%name)//' and leaves their form open, but does not '// &
            'carry to the held-out tests: only every test fitted together tells whether its parameters or '// &
            'its form failed there.')
      case (joint_not_carried)
         call add_line(lines, 'Effects lower the fit tests'' BIC, none of a plausible, resolved magnitude '// &
            'taking their structured gap to its floor, and none is confirmed on the held-out tests, which '// &
            'show a gap against their noise alone ('// &
            real_str(res%gap_held_noise, 'es10.3')//' against '//real_str(res%floor_held_noise, 'es10.3')// &
            '): only every test fitted together tells which effect explains most of every test.')
      case (joint_loose)
         call add_line(lines, trim(res%effects(res%leading)%name)//' rests on its prediction of the held-out '// &
            'tests alone (the fit tests show no structured gap), while the baseline''s constants sit at a '// &
            'search bound: the prediction tests those constants as much as the effect.')
      case default
         ! (as the verdict words it, see why_note)
         if (fit_effect_not_carried(res)) then
            call add_line(lines, 'An effect takes the fit tests'' structured gap to its floor but does not '// &
               'carry to the held-out tests: the fit tests leave its form open, so their prediction confirms '// &
               'nothing.')
         else
            ! Against their noise alone: their structured gap in section 1 is counted against a
            ! floor that holds the fitted constants' uncertainty too, and can be 0 there
            call add_line(lines, 'The fit tests show no structured gap that an effect explains and the held-out '// &
               'tests show one against their noise alone ('//real_str(res%gap_held_noise, 'es10.3')// &
               ' against '//real_str(res%floor_held_noise, 'es10.3')//', without the fitted constants'' '// &
               'uncertainty), so nothing fitted to the fit tests alone can be confirmed by the prediction.')
         end if
      end select
      call add_line(lines, 'The diagnosis again with every test '// &
         'fitted, from the baseline''s constants. An effect found here explains tests it was fitted to, '// &
         'which is weaker evidence than a prediction; a test that shows it on its own confirms it.')
      call add_line(lines, '')
      call add_line(lines, 'Baseline of every test: objective '//real_str(jres%f0, 'es10.3')//', structured gap '// &
         real_str(jres%gap_fit, 'es10.3')//' against its floor '//real_str(jres%floor_fit, 'es10.3')// &
         '; per test:')
      do i = 1, size(jres%names)
         call add_line(lines, '- '//trim(jres%names(i))//': '//real_str(jres%per_test0(i), 'es10.3'))
      end do
      if (allocated(jres%rebased_by)) call add_line(lines, 'This baseline was fitted again from the '// &
         'constants of the '//jres%rebased_by//' refit of this stage: without their effect they fit every '// &
         'test better than the stage''s first baseline (objective '//real_str(jres%f0_left, 'es10.3')// &
         '), and every effect here is judged against the optimum of the constants.')
      call add_line(lines, '')
      call add_line(lines, '**Verdict of this stage:** '//jres%verdict)
      call add_line(lines, '')
      call which_section(lines, jres, opts, '### Which effect, every test fitted')
      call separate_section(lines, jres, '### Which test would tell them apart, every test fitted')
      end associate
   end subroutine joint_section

   !> The last section, where an effect explained the fit tests but did not carry to the
   !> held-out tests (see held_own in usharp_diagnose): each held-out test diagnosed beside
   !> the fit tests with that effect carried, its per-specimen report one heading down
   subroutine own_section(lines, res)
      character(len=report_line_len), allocatable, intent(inout) :: lines(:)
      type(diagnose_result), intent(in) :: res
      integer :: j, n
      if (res%own_base == 0 .or. .not. allocated(res%own_report)) return
      n = 4 + count([has_separation(res), allocated(res%joint)])
      call add_line(lines, '')
      call add_line(lines, '## '//str(n)//'. What the held-out tests have of their own')
      call add_line(lines, '')
      associate (e => res%effects(res%own_base))
         call add_line(lines, carried_clause(e)//'. The prediction tries one effect at a time; here each '// &
            'held-out test is diagnosed as a specimen beside the fit tests (its "replicates"), '// &
            'with '//trim(e%name)//' and its refit''s constants carried to it, and each effect fitted to it alone '// &
            'on top of them: what it has of its own beyond '//trim(e%name)//'.')
      end associate
      do j = 1, size(res%own_report)
         ! (one heading down: the specimen's title is a subsection here)
         if (index(res%own_report(j), '# ') == 1) then
            call add_line(lines, '##'//trim(res%own_report(j)))
         else
            call add_line(lines, trim(res%own_report(j)))
         end if
      end do
   end subroutine own_section

   !> Section 4, when effects explain the gap equally well or the fit tests leave the
   !> leader's held-out prediction open: the candidate tests that would separate them
   subroutine separate_section(lines, res, heading)
      character(len=report_line_len), allocatable, intent(inout) :: lines(:)
      type(diagnose_result), intent(in) :: res
      character(len=*), intent(in), optional :: heading  !< instead of section 4's
      integer :: j, c
      if (.not. has_separation(res)) return
      call add_line(lines, '')
      if (present(heading)) then
         call add_line(lines, heading)
      else
         call add_line(lines, '## 4. Which test would tell them apart')
      end if
      call add_line(lines, '')
      call add_line(lines, 'Each candidate simulated with each effect''s refit (a per-test parameter at the fit '// &
         'tests'' mean); D = sum of the squared difference of the two responses over the noise '// &
         'variance of the fit tests'' data scaled to the candidate''s peak (expected discrimination, '// &
         'a chi-square: above about 10 the test separates them at that noise; the constants are not '// &
         'refitted to the candidate, so D is an upper estimate).')
      if (allocated(res%seps)) then
         do j = 1, size(res%seps)
            associate (sp => res%seps(j))
               call candidate_table(sp, trim(res%effects(sp%a)%name)//' vs '//trim(res%effects(sp%b)%name))
            end associate
         end do
      end if
      if (res%pin%best > 0) then
         associate (e => res%effects(res%pin%a))
            call add_line(lines, '')
            call add_line(lines, 'The fit tests leave the held-out prediction of '//trim(e%name)//' open: of the '// &
               'end points of its refit they cannot tell apart, one carries '// &
               real_str(100.0_dp*e%shrink_alike_lo, 'f0.1')//' % of the held-out gap, one '// &
               real_str(100.0_dp*e%shrink_alike_hi, 'f0.1')//' %. Each candidate simulated with both; '// &
               'a test that tells them apart, added to the fit tests, would fix the parameters that '// &
               'the held-out prediction depends on.')
            call candidate_table(res%pin, trim(e%name)//' at '//real_str(100.0_dp*e%shrink_alike_lo, 'f0.1')// &
               ' vs '//real_str(100.0_dp*e%shrink_alike_hi, 'f0.1')//' %')
         end associate
      end if
   contains
      !> One table: each candidate's D for the pair named in what
      subroutine candidate_table(sp, what)
         type(separation_type), intent(in) :: sp
         character(len=*), intent(in) :: what
         call add_line(lines, '')
         call add_line(lines, '| candidate test | D: '//what//' |')
         call add_line(lines, '|---|---|')
         do c = 1, size(sp%d)
            call add_line(lines, '| '//trim(sp%names(c))//trim(merge(' (best)', '       ', c == sp%best))// &
               ' | '//real_str(sp%d(c), 'es9.2')//' |')
         end do
      end subroutine candidate_table
   end subroutine separate_section

   !> Noise part of test i's objective
   real(dp) function region_noise(res, i) result(v)
      type(diagnose_result), intent(in) :: res
      integer, intent(in) :: i
      integer :: j
      v = 0.0_dp
      do j = 1, size(res%regions)
         if (res%regions(j)%label /= 'whole test') cycle
         if (res%regions(j)%test(1:len_trim(res%names(i))) /= trim(res%names(i))) cycle
         v = res%regions(j)%noise
         exit
      end do
   end function region_noise

   !> Objective of the set (fit or held-out) that region i belongs to
   real(dp) function set_total(res, i) result(v)
      type(diagnose_result), intent(in) :: res
      integer, intent(in) :: i
      if (index(res%regions(i)%test, '(held out)') > 0) then
         v = max(sum(res%per_test0, res%held), tiny(1.0_dp))
      else
         v = max(sum(res%per_test0, .not. res%held), tiny(1.0_dp))
      end if
   end function set_total

   !> The report (lines, also written to dir/report.md), the CSV tables and the plots in dir
   subroutine write_report(dir, res, opts, lines, error)
      !> Directory of the report (made when absent)
      character(len=*), intent(in) :: dir
      type(diagnose_result), intent(in) :: res
      type(diagnose_options), intent(in) :: opts
      !> The report, with a last line naming what was written
      character(len=report_line_len), allocatable, intent(out) :: lines(:)
      type(error_type), allocatable, intent(out) :: error
      logical :: plotted
      lines = diagnose_report(res, opts)
      call make_dir(dir, error)
      if (allocated(error)) return
      call write_tables(dir, res, error)
      if (allocated(error)) return
      call draw_plots(dir, res, plotted)
      if (plotted) then
         lines = [character(len=report_line_len) :: lines, '', '## Plots', '', &
                  '![residual against time](residuals.png)', '', &
                  '![fit before and after the leading effect](fit.png)']
      else
         lines = [character(len=report_line_len) :: lines, '', '## Plots', '', &
                  'Plots not drawn: gnuplot was not found or failed (scripts/setup.sh installs it);'// &
                  ' the data are in residuals.csv.']
      end if
      call write_lines(join_path(dir, 'report.md'), lines, error)
      if (allocated(error)) return
      ! Times vary from run to run: in the log, not in the report
      call write_lines(join_path(dir, 'steps.csv'), diagnose_log(res), error)
      if (allocated(error)) return
      lines = [character(len=report_line_len) :: lines, '', 'wrote '//join_path(dir, 'report.md')//', '// &
               'regions.csv, effects.csv, residuals.csv, steps.csv'//trim(merge(', *.png', '       ', plotted))]
   end subroutine write_report

   !> The effect whose curve residuals.csv and fit.png show: the leader, else the first
   !> refitted; 0 where none was refitted
   pure integer function curve_effect(res) result(lead)
      type(diagnose_result), intent(in) :: res
      integer :: j
      lead = res%leading
      if (lead /= 0) return
      do j = size(res%effects), 1, -1
         if (res%effects(j)%refitted) lead = j
      end do
   end function curve_effect

   !> Whether the effect curve is the verdict's leader fitted with every test (the stage
   !> that fits every test decides the verdict and names one)
   pure logical function joint_curve(res)
      type(diagnose_result), intent(in) :: res
      joint_curve = joint_decides(res)
      if (.not. joint_curve) return
      joint_curve = res%joint%leading > 0
      if (.not. joint_curve) return
      joint_curve = allocated(res%joint%effects(res%joint%leading)%y) .and. allocated(res%y_base)
      if (joint_curve) joint_curve = size(res%joint%effects(res%joint%leading)%y) == size(res%y_base)
   end function joint_curve

   !> The effect curve's name in the plots: the verdict's leader fitted with every test, or
   !> the effect whose curve it is with whether it was confirmed
   function curve_label(res) result(text)
      type(diagnose_result), intent(in) :: res
      character(len=:), allocatable :: text
      integer :: lead
      lead = curve_effect(res)
      if (joint_curve(res)) then
         text = 'with '//trim(res%joint%effects(res%joint%leading)%name)//' (every test fitted)'
      else if (lead > 0) then
         text = 'with '//trim(res%effects(lead)%name)
         if (.not. res%effects(lead)%confirmed) text = text//' (not confirmed)'
      else
         text = 'no effect refitted'
      end if
   end function curve_label

   !> regions.csv, effects.csv, residuals.csv
   subroutine write_tables(dir, res, error)
      character(len=*), intent(in) :: dir
      type(diagnose_result), intent(in) :: res
      type(error_type), allocatable, intent(out) :: error
      ! (long enough for a test name of its greatest length, quoted, and the numbers)
      integer, parameter :: row_len = 600
      character(len=row_len), allocatable :: rows(:)
      integer :: i, lead
      logical :: joint
      allocate (rows(0))
      rows = [character(len=row_len) :: rows, 'test,region,points,objective,noise_part,structured_gap,rms,bias,runs_z,structured']
      do i = 1, size(res%regions)
         associate (r => res%regions(i))
            rows = [character(len=row_len) :: rows, csv_field(trim(r%test))//','//csv_field(trim(r%label))//','// &
               str(r%n)//','// &
               real_str(r%ssr, 'es12.5')//','//real_str(r%noise, 'es12.5')//','//real_str(r%gap, 'es12.5')// &
               ','//real_str(r%rms, 'es12.5')//','//real_str(r%bias, 'es12.5')//','//real_str(r%z, 'f0.2')// &
               ','//trim(merge('yes', 'no ', r%structured))]
         end associate
      end do
      call write_lines(join_path(dir, 'regions.csv'), rows, error)
      if (allocated(error)) return
      deallocate (rows)
      allocate (rows(0))
      ! Each stage's effects: the fit tests', and where every test was fitted too (which then
      ! decides the verdict) that stage's; leads: the stage's leader
      ! (its header begins with the mark a later run knows it by)
      rows = [character(len=row_len) :: rows, trim(report_marks(4))//'predicted_fall,predicted_dbic,'// &
              'refitted,objective_after,daic,dbic,gap_removed_fit,gap_removed_held_out,confirmed,leads,'// &
              'chi_square_low_end,power_low_end,power_095_at_low_end_times,finding_test,finding_test_power']
      call effect_rows('fit tests', res)
      if (allocated(res%joint)) call effect_rows('every test', res%joint)
      call write_lines(join_path(dir, 'effects.csv'), rows, error)
      if (allocated(error)) return
      deallocate (rows)
      ! The curves: data, baseline, and with the leading (else the first refitted) effect
      lead = curve_effect(res)
      ! (decided once, not at every point)
      joint = joint_curve(res)
      allocate (rows(size(res%t) + 1))
      rows(1) = 'test,held_out,t_s,class,data,baseline,with_effect,class_id,cycle,inelastic'
      do i = 1, size(res%t)
         rows(i + 1) = csv_field(trim(res%names(res%test_of(i))))//','// &
            trim(merge('yes', 'no ', res%held(res%test_of(i))))//','//real_str(res%t(i), 'es14.7')//','// &
            trim(class_names(res%cls(i)))//','//real_str(res%y_ex(i), 'es14.7')//','// &
            real_str(res%y_base(i), 'es14.7')//','//real_str(effect_curve(i), 'es14.7')//','// &
            str(res%cls(i))//','//str(res%cycle(i))//','//trim(merge('no ', 'yes', res%elastic(i)))
      end do
      call write_lines(join_path(dir, 'residuals.csv'), rows, error)
   contains
      real(dp) function effect_curve(i) result(y)
         integer, intent(in) :: i
         y = res%y_base(i)
         if (joint) then
            y = res%joint%effects(res%joint%leading)%y(i)
         else if (lead > 0) then
            y = res%effects(lead)%y(i)
         end if
      end function effect_curve

      !> The rows of effects.csv of one stage's result r
      subroutine effect_rows(stage, r)
         character(len=*), intent(in) :: stage
         type(diagnose_result), intent(in) :: r
         character(len=:), allocatable :: held
         integer :: k
         do k = 1, size(r%effects)
            associate (e => r%effects(k))
               ! (empty where no test is held out, as the report's '-')
               held = ''
               if (any(r%held)) held = real_str(e%shrink_held, 'f0.4')
               rows = [character(len=row_len) :: rows, stage//','//str(k)//','//csv_field(trim(e%name))//','// &
                  str(e%q)//','//real_str(e%pred_drop, 'es12.5')//','//real_str(e%pred_dbic, 'f0.2')//','// &
                  trim(merge('yes', 'no ', e%refitted))//','//real_str(e%f_after, 'es12.5')//','// &
                  real_str(e%daic, 'f0.2')//','//real_str(e%dbic, 'f0.2')//','// &
                  real_str(e%shrink_fit, 'f0.4')//','//held//','// &
                  trim(merge('yes', 'no ', e%confirmed))//','//trim(merge('yes', 'no ', k == r%leading))// &
                  ','//real_str(e%lambda_low, 'es12.5')//','// &
                  real_str(e%power_low, 'f0.4')//','//real_str(e%hidden%times, 'f0.3')//','// &
                  csv_field(trim(e%hidden%test))//','//real_str(e%hidden%power, 'f0.4')]
            end associate
         end do
      end subroutine effect_rows
   end subroutine write_tables

   !> residuals.png (data - baseline against time, one panel per test) and fit.png (data,
   !> baseline and with the leading effect) with gnuplot; plotted false if it could not
   subroutine draw_plots(dir, res, plotted)
      character(len=*), intent(in) :: dir
      type(diagnose_result), intent(in) :: res
      logical, intent(out) :: plotted
      character(len=512), allocatable :: gp(:)
      type(error_type), allocatable :: error
      type(process_result) :: proc
      character(len=:), allocatable :: base, csv
      character(len=max(16, len(dir) + 16)) :: argv(3)
      character(len=*), parameter :: pngs(2) = [character(len=13) :: 'residuals.png', 'fit.png']
      integer :: k
      logical :: gone
      ! The folder reaches gnuplot only inside quoted strings, and never as a file name that
      ! begins with < or | (which gnuplot would run as a command)
      base = dir
      if (len(base) == 0) base = '.'
      if (base(1:1) /= '/') base = './'//base
      csv = gnuplot_string(join_path(base, 'residuals.csv'))
      ! gnuplot draws under temporary names, renamed into place once both are whole: a run
      ! stopped meanwhile leaves the earlier plots as plots.gp records them
      call write_lines(join_path(dir, 'plots.gp.run'), script('.part'), error)
      plotted = .false.
      if (.not. allocated(error)) then
         ! gnuplot found on the PATH by env, the script passed as an argument: no shell
         argv(1) = '/usr/bin/env'
         argv(2) = 'gnuplot'
         argv(3) = join_path(base, 'plots.gp.run')
         call run_process(argv, '.', '/dev/null', '/dev/null', 600.0_dp, 5.0_dp, proc)
         plotted = proc%how == proc_exited .and. proc%code == 0
      end if
      gone = remove_file(join_path(dir, 'plots.gp.run'))
      do k = 1, size(pngs)
         if (plotted) then
            call rename_file(join_path(dir, trim(pngs(k))//'.part'), join_path(dir, trim(pngs(k))), error)
            plotted = .not. allocated(error)
         end if
      end do
      gp = script('')
      ! The script records what it drew, so that a later run knows these plots for its own
      ! (and a user's file of their names for another's)
      if (plotted) gp = [character(len=512) :: gp, drawn_line(dir, 'residuals.png'), drawn_line(dir, 'fit.png')]
      if (plotted) plotted = all(len_trim(gp(size(gp) - 1:)) > 0)
      call write_lines(join_path(dir, 'plots.gp'), gp, error)
      plotted = plotted .and. .not. allocated(error)
      if (.not. plotted) then
         ! Neither half-drawn plots nor an earlier run's are left behind
         do k = 1, size(pngs)
            gone = remove_file(join_path(dir, trim(pngs(k))//'.part'))
            gone = remove_file(join_path(dir, trim(pngs(k))))
         end do
      end if
   contains
      !> The gnuplot script, its plots named with suffix after .png
      function script(suffix) result(gp)
         character(len=*), intent(in) :: suffix
         character(len=512), allocatable :: gp(:)
         character(len=:), allocatable :: with
         integer :: i, nt
         nt = size(res%names)
         allocate (gp(0))
         gp = [character(len=512) :: gp, "set datafile separator ','", &
               "set linetype 1 lc rgb '#c03030'", "set linetype 2 lc rgb '#3050c0'", &
               "set linetype 3 lc rgb '#30a040'", "set linetype 4 lc rgb 'black'", 'set terminal pngcairo size 1200,'// &
               str(300*nt)//' font ",9"', "set output "//gnuplot_string(join_path(base, 'residuals.png'//suffix)), &
               'set multiplot layout '//str(nt)//',1', 'set key off', 'set xlabel "time (s)"']
         do i = 1, nt
            gp = [character(len=512) :: gp, 'set title "'//trim(res%names(i))//held_mark(i)//': data - baseline, '// &
                  trim(res%unit(i))//'; red loading, blue unloading, green reversal, black hold"', &
                  "plot "//csv//" every ::1 using "//own_x(i)//":($5-$6):8 with points pt 7 ps 0.3 lc variable"]
         end do
         ! (the legend beside the panel, where it hides no data)
         gp = [character(len=512) :: gp, 'unset multiplot', "set output "// &
               gnuplot_string(join_path(base, 'fit.png'//suffix)), 'set multiplot layout '//str(nt)//',1', &
               'set key outside right top']
         with = curve_label(res)
         do i = 1, nt
            gp = [character(len=512) :: gp, 'set title "'//trim(res%names(i))//held_mark(i)//'"', &
                  'set ylabel "'//trim(res%unit(i))//'"', &
                  "plot "//csv//" every ::1 using "//own_x(i)//":5 with dots "// &
                  "lc rgb 'black' title 'data', '' every ::1 using "//own_x(i)//":6 with lines lc rgb 'blue' "// &
                  "title 'baseline', '' every ::1 using "//own_x(i)//":7 with lines lc rgb 'red' title '"// &
                  with//"'"]
         end do
         gp = [character(len=512) :: gp, 'unset multiplot']
      end function script

      !> ' (held out: the baseline is its prediction)' for a held-out test i, else ''
      function held_mark(i) result(text)
         integer, intent(in) :: i
         character(len=:), allocatable :: text
         text = ''
         if (allocated(res%held)) then
            if (i <= size(res%held)) then
               if (res%held(i)) text = ' (held out: the baseline is its prediction)'
            end if
         end if
      end function held_mark

      !> Time of test i's points only (other tests' undefined): each panel spans its own test
      function own_x(i) result(text)
         integer, intent(in) :: i
         character(len=:), allocatable :: text
         text = "(strcol(1) eq '"//trim(res%names(i))//"' ? $3 : 1/0)"
      end function own_x
   end subroutine draw_plots

   !> A ratio of mean squares as text: fixed with two decimals up to 1e4, else in E format
   !> (3.3E+14, not 331042219086019.38)
   pure function ratio_text(x) result(text)
      real(dp), intent(in) :: x
      character(len=:), allocatable :: text
      if (abs(x) < 1.0e4_dp) then
         text = real_str(x, 'f0.2')
      else
         text = real_str(x, 'es9.2')
      end if
   end function ratio_text
   !> Test i's noise correlation (noise_correlation) as a table cell; '-' where not known
   pure function corr_cell(res, i) result(text)
      type(diagnose_result), intent(in) :: res
      integer, intent(in) :: i
      character(len=:), allocatable :: text
      text = '-'
      if (.not. allocated(res%noise_corr)) return
      if (res%noise_corr(i) > 0.0_dp) text = real_str(res%noise_corr(i), 'f0.2')
   end function corr_cell
end module usharp_diagnose_report
