!> The &diagnose group: settings of `usharp diagnose`. The held-out tests are resolved here
!> against the &test names, once: every other part of usharp sees a mask over the tests.
module usharp_input_diagnose
   use usharp_kinds, only: dp
   use usharp_error, only: error_type, fatal_error, stat_input
   use usharp_namelist, only: nml_file, group_text, find_group, group_error, read_error, check_length, &
                              value_len, max_list
   use usharp_input_test, only: test_config
   use usharp_strings, only: lower, real_str
   implicit none
   private

   public :: diagnose_config, read_diagnose_group, write_diagnose_defaults, check_holdout, specimen_unused

   !> Longest effect name
   integer, parameter :: effect_len = 64

   !> Diagnosis settings (&diagnose group); effect names are resolved by the diagnose command
   type :: diagnose_config
      !> Per &test, in file order: held out of the fit (given by name as holdout = 'a', 'b')
      logical, allocatable :: holdout(:)
      character(len=effect_len) :: effects(max_list) = ''  !< effects considered (none given: all)
      character(len=effect_len) :: rows(max_list) = ''     !< self-check rows: injected effects, 'none' clean
      integer :: n_refit = 3                       !< leading candidates refitted
      integer :: refit_starts = 1                  !< screening end points each refit starts from
      integer :: global_starts = 4                 !< Latin-hypercube starts of the constants (baseline and refits)
                                                   !< when no local refit reaches the noise level
      logical :: cross_starts = .true.             !< a refit ending above another reruns from its constants
      real(dp) :: dlnE_dT = -4.0e-4_dp             !< 1/K, temperature slope of ln E
      real(dp) :: gamma3 = 200.0_dp                !< -, second back stress recovery (screening)
      real(dp) :: confirm_shrink = 0.5_dp          !< held-out structured gap removed to confirm
      integer :: reps = 10                         !< self-check repetitions per effect
      integer :: seed = 1                          !< self-check seed
      real(dp) :: noise = 0.01_dp                  !< self-check noise, fraction of the peak
      !> Per-specimen mode: the test diagnosed against the others (its replicates), 'all' for
      !> each test in turn; blank: the diagnosis of the fit
      character(len=64) :: specimen = ''
      logical :: present = .false.                 !< the input file has the group
   end type diagnose_config

contains

   !> Read &diagnose (optional) into diagnose; tests: the file's tests, to resolve holdout
   subroutine read_diagnose_group(file, tests, diagnose, error)
      type(nml_file), intent(in) :: file
      type(test_config), intent(in) :: tests(:)
      type(diagnose_config), intent(out) :: diagnose
      type(error_type), allocatable, intent(out) :: error
      character(len=value_len) :: holdout(max_list), effects(max_list), rows(max_list)
      character(len=value_len) :: specimen
      integer :: ios, k, i, j
      character(len=512) :: msg
      character(len=:), allocatable :: lines(:)
      character(len=:), allocatable :: where
      allocate (diagnose%holdout(size(tests)))
      diagnose%holdout = .false.
      k = find_group(file, 'diagnose')
      if (k == 0) return
      diagnose%present = .true.
      call group_text(file, k, lines)
      call diagnose_namelist(diagnose, holdout, effects, rows, specimen, ios, msg, text=lines)
      if (ios /= 0) then
         call read_error(error, file, k, 'diagnose', ios, msg, reread)
         return
      end if
      where = file%path//': &diagnose: '
      do i = 1, max_list
         call check_length(error, where, 'holdout', holdout(i))
         call check_length(error, where, 'effects', effects(i)(:effect_len + 1))
         call check_length(error, where, 'rows', rows(i)(:effect_len + 1))
      end do
      call check_length(error, where, 'specimen', specimen(:len(diagnose%specimen) + 1))
      if (allocated(error)) return
      diagnose%effects = effects
      diagnose%rows = rows
      ! An effect named twice would be fitted and reported twice
      do i = 2, max_list
         do j = 1, i - 1
            if (len_trim(effects(i)) > 0 .and. lower(effects(j)) == lower(effects(i))) then
               call fail("effects names '"//trim(effects(i))//"' twice")
               return
            end if
            if (len_trim(rows(i)) > 0 .and. lower(rows(j)) == lower(rows(i))) then
               call fail("rows names '"//trim(rows(i))//"' twice")
               return
            end if
            if (len_trim(holdout(i)) > 0 .and. holdout(j) == holdout(i)) then
               call fail("holdout names '"//trim(holdout(i))//"' twice")
               return
            end if
         end do
      end do
      do i = 1, max_list
         if (len_trim(holdout(i)) == 0) cycle
         j = findloc([(tests(k)%name == trim(holdout(i)), k=1, size(tests))], .true., 1)
         if (j == 0) then
            call fail("holdout: no &test is named '"//trim(holdout(i))//"'")
            return
         end if
         diagnose%holdout(j) = .true.
      end do
      if (diagnose%n_refit < 1) then
         call fail('n_refit must be >= 1')
      else if (diagnose%refit_starts < 1) then
         call fail('refit_starts must be >= 1')
      else if (diagnose%global_starts < 0) then
         call fail('global_starts must be >= 0')
      else if (diagnose%reps < 1) then
         call fail('reps must be >= 1')
      else if (.not. (diagnose%gamma3 > 0.0_dp)) then
         call fail('gamma3 = '//real_str(diagnose%gamma3, 'g0.4')//' must be > 0')
      else if (.not. (diagnose%noise > 0.0_dp)) then
         call fail('noise = '//real_str(diagnose%noise, 'g0.4')//' must be > 0')
      else if (diagnose%noise >= 0.5_dp) then
         ! A share of the peak stress: 5.0 is 500 % (is it in percent?)
         call fail('noise = '//real_str(diagnose%noise, 'g0.4')//' is a share of the peak stress '// &
                   '(0.01 for 1 %), below 0.5')
      else if (.not. (abs(diagnose%dlne_dt) < 0.1_dp)) then
         ! d ln E / dT of metals is some -1e-4 to -1e-3 /K; beyond 0.1 /K the temperature
         ! effect's modulus change swamps every other
         call fail('dlnE_dT = '//real_str(diagnose%dlne_dt, 'es10.3')//' 1/K is no metal''s '// &
                   '(about -4e-4 1/K); |dlnE_dT| < 0.1')
      else if (.not. (diagnose%confirm_shrink > 0.0_dp .and. diagnose%confirm_shrink <= 1.0_dp)) then
         call fail('confirm_shrink must lie in (0, 1]')
      end if
   contains
      subroutine fail(text)
         character(len=*), intent(in) :: text
         call group_error(error, file%path, 'diagnose', text)
      end subroutine fail

      subroutine reread(lines, ios, msg)
         character(len=*), intent(in) :: lines(:)
         integer, intent(out) :: ios
         character(len=*), intent(out) :: msg
         type(diagnose_config) :: scratch
         character(len=value_len) :: h(max_list), e(max_list), r(max_list), s
         call diagnose_namelist(scratch, h, e, r, s, ios, msg, text=lines)
      end subroutine reread
   end subroutine read_diagnose_group

   !> A diagnosis predicts held-out tests from a fit of the others: both sets must be non-empty
   pure subroutine check_holdout(diagnose, path, error)
      type(diagnose_config), intent(in) :: diagnose
      character(len=*), intent(in) :: path  !< the input file
      type(error_type), allocatable, intent(out) :: error
      if (.not. any(diagnose%holdout) .and. .not. diagnose%present) then
         call fatal_error(error, path//': group &diagnose is missing (its holdout names the tests '// &
            "to predict, held out of the fit, or specimen = '<test>' one test to set against the others)", &
            stat_input)
      else if (.not. any(diagnose%holdout)) then
         call group_error(error, path, 'diagnose', 'holdout: the held-out set is empty; '// &
            'name the tests to predict (held out of the fit) with holdout, or one test to set '// &
            "against the others with specimen = '<test>' (or 'all')")
      else if (all(diagnose%holdout)) then
         call group_error(error, path, 'diagnose', 'holdout: every test is held out; '// &
            'nothing is left to fit')
      end if
   end subroutine check_holdout

   !> Write &diagnose with its defaults to unit
   subroutine write_diagnose_defaults(unit)
      integer, intent(in) :: unit
      type(diagnose_config) :: diagnose
      character(len=value_len) :: holdout(max_list), effects(max_list), rows(max_list), specimen
      integer :: ios
      character(len=512) :: msg
      call diagnose_namelist(diagnose, holdout, effects, rows, specimen, ios, msg, unit=unit)
   end subroutine write_diagnose_defaults

   !> The settings of d, given other than their defaults, that the per-specimen mode does not
   !> use (they set the diagnosis of held-out tests and its self-check), comma-separated
   pure function specimen_unused(d) result(names)
      type(diagnose_config), intent(in) :: d
      character(len=:), allocatable :: names
      type(diagnose_config) :: def
      names = ''
      if (allocated(d%holdout)) then
         if (any(d%holdout)) names = names//', holdout'
      end if
      if (d%n_refit /= def%n_refit) names = names//', n_refit'
      if (d%refit_starts /= def%refit_starts) names = names//', refit_starts'
      if (d%global_starts /= def%global_starts) names = names//', global_starts'
      if (d%cross_starts .neqv. def%cross_starts) names = names//', cross_starts'
      if (d%confirm_shrink /= def%confirm_shrink) names = names//', confirm_shrink'
      if (any(d%rows /= def%rows)) names = names//', rows'
      if (d%reps /= def%reps) names = names//', reps'
      if (d%seed /= def%seed) names = names//', seed'
      if (d%noise /= def%noise) names = names//', noise'
      if (len(names) > 0) names = names(3:)
   end function specimen_unused

   !> The &diagnose namelist, starting from diagnose (no test held out): read from text or
   !> written to unit. The lists come back as given, to be checked and resolved.
   subroutine diagnose_namelist(settings, holdout, effects, rows, specimen_given, ios, msg, text, unit)
      type(diagnose_config), intent(inout) :: settings
      character(len=value_len), intent(out) :: holdout(max_list), effects(max_list), rows(max_list)
      character(len=*), intent(out) :: specimen_given
      integer, intent(out) :: ios
      character(len=*), intent(out) :: msg
      character(len=*), intent(in), optional :: text(:)
      integer, intent(in), optional :: unit
      real(dp) :: dlnE_dT, gamma3, confirm_shrink, noise
      integer :: n_refit, refit_starts, global_starts, reps, seed
      logical :: cross_starts
      character(len=len(settings%specimen) + 1) :: specimen
      namelist /diagnose/ holdout, effects, rows, n_refit, refit_starts, global_starts, dlnE_dT, gamma3, &
         cross_starts, confirm_shrink, reps, seed, noise, specimen
      holdout = ''
      specimen = settings%specimen
      effects = settings%effects
      rows = settings%rows
      n_refit = settings%n_refit
      refit_starts = settings%refit_starts
      global_starts = settings%global_starts
      cross_starts = settings%cross_starts
      dlnE_dT = settings%dlnE_dT
      gamma3 = settings%gamma3
      confirm_shrink = settings%confirm_shrink
      reps = settings%reps
      seed = settings%seed
      noise = settings%noise
      ios = 0
      msg = ''
      if (present(text)) read (text, nml=diagnose, iostat=ios, iomsg=msg)
      if (present(unit)) write (unit, nml=diagnose, iostat=ios, iomsg=msg)
      settings%n_refit = n_refit
      settings%refit_starts = refit_starts
      settings%global_starts = global_starts
      settings%cross_starts = cross_starts
      settings%dlnE_dT = dlnE_dT
      settings%gamma3 = gamma3
      settings%confirm_shrink = confirm_shrink
      settings%reps = reps
      settings%seed = seed
      settings%noise = noise
      specimen_given = specimen
      settings%specimen = specimen
   end subroutine diagnose_namelist

end module usharp_input_diagnose
