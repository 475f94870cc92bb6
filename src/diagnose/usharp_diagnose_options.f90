!> Settings of a diagnosis: the &diagnose group with its names resolved (tests held out,
!> catalogue effects considered, self-check rows) and the thresholds of the verdict
module usharp_diagnose_options
   use usharp_kinds, only: dp
   use usharp_error, only: error_type, fatal_error, stat_input
   use usharp_config, only: run_config
   use usharp_effects, only: effect_info, effect_catalogue, n_effects, effect_index, effect_acts, &
                             effect_acts_why
   implicit none
   private

   public :: diagnose_options, diagnose_options_of, bic_margin, gap_z, rival_share, corr_lag, correlated_ratio

   !> BIC must fall by more than this for an effect to be significant (strong evidence)
   real(dp), parameter :: bic_margin = 10.0_dp
   !> The lag (samples) of the second differences that test a residual's noise for
   !> correlation (noise_correlation), and the ratio of its sd to that of neighbours above
   !> which the noise reads as correlated: the floors and BIC assume independent noise
   integer, parameter :: corr_lag = 5
   real(dp), parameter :: correlated_ratio = 2.0_dp
   !> A set of tests has a structured gap only above this many standard errors of the gap
   !> that noise alone leaves (on a 600-point test that standard error is 10 % of the noise
   !> part: a fixed fraction of the noise part is no measure of it)
   real(dp), parameter :: gap_z = 3.0_dp
   !> A screened effect whose predicted fall of the objective is at least this share of the
   !> leading ones' is refitted with them: over 2666 refits in 596 self-check cases the fall a
   !> refit reached was 0.86 of the screening's prediction at the 10th percentile and 1.08 at the
   !> median, so a candidate predicted at 0.8 of the leader can end ahead of it
   real(dp), parameter :: rival_share = 0.8_dp

   !> Settings of a diagnosis: the &diagnose group's (cfg%diagnose, where their defaults are;
   !> the held-out tests are cfg%diagnose%holdout) with names resolved, and the algorithm's own
   type :: diagnose_options
      integer, allocatable :: effects(:)     !< catalogue effects considered
      !> catalogue effects left out because they do not act on the model (effect_acts)
      integer, allocatable :: inert(:)
      character(len=120), allocatable :: inert_why(:)  !< why each does not act, in words
      integer, allocatable :: rows(:)        !< self-check: effects injected (0: clean data)
      integer :: n_refit                     !< leading candidates refitted
      real(dp) :: dlnE_dT                    !< 1/K, temperature slope of ln E
      real(dp) :: gamma3                     !< -, second back stress recovery in screening
      real(dp) :: confirm_shrink             !< held-out structured gap removed to confirm
      integer :: max_evals = 3000            !< per refit
      integer :: refit_starts                !< screening end points a refit starts from
      !> Latin-hypercube starts of the constants over the &fit multi-start box, run for the
      !> baseline and for every refit when no significant local refit brings the fit tests'
      !> structured gap down to the noise level (0: local only)
      integer :: global_starts
      !> A refit that ends above another runs again from that one's constants
      logical :: cross_starts
      !> Spread the starts of each global stage over the MPI ranks (every rank runs the
      !> diagnosis); not inside a self-check repetition, which runs on one rank
      logical :: over_ranks = .false.
      !> Every test fitted, none held out: the stage that asks which effect explains a gap
      !> the held-out tests show and the fit tests do not (set by the diagnosis itself)
      logical :: joint = .false.
   end type diagnose_options

contains

   !> The options of cfg's &diagnose group with names resolved: unknown effects are errors
   !> naming the file, group and variable; no effects given: the whole catalogue
   subroutine diagnose_options_of(cfg, opts, error)
      !> Configuration read from the deck
      type(run_config), intent(in) :: cfg
      !> Resolved settings
      type(diagnose_options), intent(out) :: opts
      type(error_type), allocatable, intent(out) :: error
      type(effect_info) :: cat(n_effects)
      logical :: acts(n_effects)
      integer :: k
      call effect_numbers(cfg, cfg%diagnose%effects, 'effects', .false., opts%effects, error)
      if (allocated(error)) return
      call effect_numbers(cfg, cfg%diagnose%rows, 'rows', .true., opts%rows, error)
      if (allocated(error)) return
      cat = effect_catalogue(1.0_dp)
      acts = [(effect_acts(cfg%model, k), k=1, n_effects)]
      ! An effect that cannot act on the model (the Miller model's drag and back stress
      ! effects on another model) would be a refit of the constants alone under its name
      if (size(opts%effects) == 0) then
         opts%effects = pack([(k, k=1, n_effects)], acts)
         opts%inert = pack([(k, k=1, n_effects)], .not. acts)
      else
         allocate (opts%inert(0))
      end if
      call refuse_inert(opts%effects, 'effects')
      if (allocated(error)) return
      allocate (opts%inert_why(size(opts%inert)))
      do k = 1, size(opts%inert)
         opts%inert_why(k) = effect_acts_why(cfg%model, opts%inert(k))
      end do
      if (size(opts%rows) == 0) opts%rows = [0, opts%effects]
      call refuse_inert(pack(opts%rows, opts%rows > 0), 'rows')
      if (allocated(error)) return
      ! A row injects an effect that the diagnosis is to name: one it does not consider can
      ! never be named
      do k = 1, size(opts%rows)
         if (opts%rows(k) == 0) cycle
         if (any(opts%effects == opts%rows(k))) cycle
         call fatal_error(error, cfg%path//": &diagnose: rows: '"//trim(cat(opts%rows(k))%name)// &
            "' is injected but effects does not list it, so the diagnosis cannot name it "// &
            '(add it to effects)', stat_input)
         return
      end do
      opts%n_refit = cfg%diagnose%n_refit
      opts%refit_starts = cfg%diagnose%refit_starts
      opts%global_starts = cfg%diagnose%global_starts
      opts%cross_starts = cfg%diagnose%cross_starts
      opts%dlnE_dT = cfg%diagnose%dlnE_dT
      opts%gamma3 = cfg%diagnose%gamma3
      opts%confirm_shrink = cfg%diagnose%confirm_shrink
   contains
      !> The first of the effects ks named in `variable` that does not act on the model: an
      !> input error
      subroutine refuse_inert(ks, variable)
         integer, intent(in) :: ks(:)
         character(len=*), intent(in) :: variable
         integer :: i
         do i = 1, size(ks)
            if (acts(ks(i))) cycle
            call fatal_error(error, cfg%path//': &diagnose: '//variable//": '"//trim(cat(ks(i))%name)// &
               "' does not act on this model: "//effect_acts_why(cfg%model, ks(i)), stat_input)
            return
         end do
      end subroutine refuse_inert
   end subroutine diagnose_options_of

   !> Catalogue numbers of the effect names given to &diagnose variable `variable` (blank
   !> entries skipped); with allow_none, 'none' is 0 (clean data)
   subroutine effect_numbers(cfg, names, variable, allow_none, ks, error)
      type(run_config), intent(in) :: cfg
      character(len=*), intent(in) :: names(:), variable
      logical, intent(in) :: allow_none
      integer, allocatable, intent(out) :: ks(:)
      type(error_type), allocatable, intent(out) :: error
      type(effect_info) :: cat(n_effects)
      integer :: i, k
      cat = effect_catalogue(1.0_dp)
      allocate (ks(0))
      do i = 1, size(names)
         if (len_trim(names(i)) == 0) cycle
         k = effect_index(names(i))
         if (k == 0 .and. .not. (allow_none .and. trim(adjustl(names(i))) == 'none')) then
            call fatal_error(error, cfg%path//': &diagnose: '//variable//": no effect is named '"// &
               trim(names(i))//"' (known: "//catalogue_names(cat)// &
               trim(merge(', none', '      ', allow_none))//')', stat_input)
            return
         end if
         ks = [ks, k]
      end do
   end subroutine effect_numbers

   pure function catalogue_names(cat) result(text)
      type(effect_info), intent(in) :: cat(:)
      character(len=:), allocatable :: text
      integer :: j
      text = trim(cat(1)%name)
      do j = 2, size(cat)
         text = text//', '//trim(cat(j)%name)
      end do
   end function catalogue_names
end module usharp_diagnose_options
