!> Regions of the residual of a deck's tests at the deck's constants, as `usharp diagnose`
!> classes them: history class and cycle from the control's kinematics, elastic or inelastic
!> from the model's inelastic rate, and the serrated-flow signature. Writes DIR/points.csv
!> (one row per point: test, time s, control, data, model, class, cycle, inelastic) and
!> prints one table per test: points, RMS, mean error and runs z of each region.
!> usage: bench_regions DECK DIR   (run from the deck's folder or give paths that resolve)
program bench_regions
   use, intrinsic :: iso_fortran_env, only: output_unit, error_unit
   use usharp_kinds, only: dp
   use usharp_error, only: error_type
   use usharp_config, only: run_config
   use usharp_input, only: read_config
   use usharp_objective, only: fit_problem, setup_problem
   use usharp_effects, only: test_effects
   use usharp_effect_problem, only: effect_problem, new_effect_problem
   use usharp_regions, only: point_classes, inelastic_points, region_of, region_stat, class_names, &
                             serration_of, serration_stat, noise_sd, kinematics_of, control_kinematics
   use usharp_strings, only: str, real_str
   use usharp_filesys, only: join_path, make_dir
   implicit none
   type(run_config) :: cfg
   type(fit_problem) :: prob
   type(effect_problem) :: ep
   type(test_effects) :: base
   type(error_type), allocatable :: e
   type(region_stat) :: st
   type(serration_stat) :: ser
   type(control_kinematics) :: kin
   character(len=512) :: deck, dir
   real(dp), allocatable :: r(:), y(:), eps(:), epsin(:), nv(:), err(:)
   integer, allocatable :: cls(:), cyc(:)
   logical, allocatable :: inel(:)
   integer :: i, k0, n, c, u, j
   logical :: ok
   if (command_argument_count() < 2) then
      write (error_unit, '(a)') 'usage: bench_regions DECK DIR'
      error stop 2
   end if
   call get_command_argument(1, deck)
   call get_command_argument(2, dir)
   call read_config(trim(deck), cfg, e)
   if (.not. allocated(e)) call setup_problem(cfg, prob, e)
   if (allocated(e)) then
      write (error_unit, '(a)') e%message
      error stop 1
   end if
   call new_effect_problem(prob, [(i, i=1, size(prob%targets))], 0, base, 1.0_dp, ep)
   allocate (r(ep%nres()), y(ep%nres()), eps(ep%nres()), epsin(ep%nres()))
   call ep%residual_at(ep%start(), r, ok, y, eps, epsin)
   if (.not. ok) error stop 'simulation failed'
   call make_dir(trim(dir), e)
   open (newunit=u, file=join_path(trim(dir), 'points.csv'), status='replace', action='write')
   write (u, '(a)') 'test,t_s,control,data,model,class,cycle,inelastic'
   k0 = 0
   do i = 1, size(prob%targets)
      associate (tg => prob%targets(i), test => cfg%tests(i))
         n = size(tg%t)
         allocate (cls(n), cyc(n))
         call point_classes(test%hist, tg%t, cls, cyc)
         kin = kinematics_of(test%hist)
         inel = inelastic_points(eps(k0 + 1:k0 + n), epsin(k0 + 1:k0 + n))
         err = tg%y_ex - y(k0 + 1:k0 + n)
         nv = spread(noise_sd(tg%y_ex)**2, 1, n)
         do j = 1, n
            write (u, '(a)') trim(test%name)//','//real_str(tg%t(j), 'es14.7')//','// &
               real_str(test%hist%value_at(tg%t(j)), 'es14.7')//','//real_str(tg%y_ex(j), 'es14.7')//','// &
               real_str(y(k0 + j), 'es14.7')//','//trim(class_names(cls(j)))//','//str(cyc(j))//','// &
               trim(merge('yes', 'no ', inel(j)))
         end do
         write (output_unit, '(a)') '', '### '//trim(test%name)//': '//str(n)//' points, '// &
            str(size(kin%tturn))//' turns, control quantum '//real_str(kin%quantum, 'es9.2')// &
            ', noise sd '//real_str(kin%noise, 'es9.2')
         write (output_unit, '(a)') '', '| region | points | RMS | mean error | runs z |', '|---|---|---|---|---|'
         call row('whole test', spread(.true., 1, n))
         do c = 1, size(class_names)
            if (any(cls == c)) call row(trim(class_names(c)), cls == c)
         end do
         call row('elastic', .not. inel)
         call row('inelastic', inel)
         do c = 1, maxval(cyc)
            if (any(cyc == c)) call row('cycle '//str(c), cyc == c)
         end do
         ser = serration_of(err, inel, count(inel)/(12*maxval(cyc)))
         write (output_unit, '(a)') '', 'oscillation of the inelastic residual: p = '//real_str(ser%p, 'es9.2')// &
            ', period '//real_str(ser%period, 'f0.1')//' samples, amplitude '//real_str(ser%amplitude, 'es9.2')
         k0 = k0 + n
         deallocate (cls, cyc)
      end associate
   end do
   close (u)
contains
   subroutine row(label, mask)
      character(len=*), intent(in) :: label
      logical, intent(in) :: mask(:)
      st = region_of('', label, mask, r(k0 + 1:k0 + size(mask)), err, nv)
      write (output_unit, '(a)') '| '//label//' | '//str(st%n)//' | '//real_str(st%rms, 'es9.2')//' | '// &
         real_str(st%bias, 'es9.2')//' | '//real_str(st%z, 'f0.1')//' |'
   end subroutine row
end program bench_regions
