!> `usharp diagnose`: the diagnosis of a fit (report.md, CSV tables, gnuplot plots in
!> <out_dir>/diagnose) and `usharp diagnose --selfcheck` on synthetic data
module usharp_cmd_diagnose
   use usharp_kinds, only: dp
   use usharp_error, only: error_type
   use usharp_strings, only: str, real_str
   use usharp_config, only: run_config
   use usharp_input, only: read_config_as
   use usharp_diagnose, only: diagnose_options, diagnose_result, diagnose_run, diagnose_report, &
                              diagnose_options_of
   use usharp_regions, only: class_names
   use usharp_selfcheck, only: selfcheck_run, selfcheck_report, selfcheck_result, selfcheck_deck
   use usharp_filesys, only: make_dir, join_path
   use usharp_output, only: write_lines
   implicit none
   private

   public :: diagnose_command, selfcheck_command

contains

   !> Diagnose the fit of path's tests at the constants of constants_file (a best.nml)
   subroutine diagnose_command(path, out_dir, constants_file, lines, error)
      character(len=*), intent(in) :: path, out_dir, constants_file
      character(len=200), allocatable, intent(out) :: lines(:)
      type(error_type), allocatable, intent(out) :: error
      type(run_config) :: cfg
      type(diagnose_options) :: opts
      type(diagnose_result) :: res
      character(len=:), allocatable :: dir
      logical :: plotted
      call read_config_as(path, constants_file, out_dir, cfg, error)
      if (allocated(error)) return
      call diagnose_options_of(cfg, opts, error)
      if (allocated(error)) return
      call diagnose_run(cfg, opts, res, error)
      if (allocated(error)) return
      lines = diagnose_report(res, opts)
      dir = join_path(cfg%out_dir, 'diagnose')
      call make_dir(dir, error)
      if (allocated(error)) return
      call write_tables(dir, res, error)
      if (allocated(error)) return
      call draw_plots(dir, res, plotted)
      if (plotted) then
         lines = [character(len=200) :: lines, '', '## Plots', '', &
                  '![residual against time](residuals.png)', '', &
                  '![fit before and after the leading effect](fit.png)']
      else
         lines = [character(len=200) :: lines, '', '## Plots', '', &
                  'Plots not drawn: gnuplot was not found or failed (scripts/setup.sh installs it);'// &
                  ' the data are in residuals.csv.']
      end if
      call write_lines(join_path(dir, 'report.md'), lines, error)
      if (allocated(error)) return
      lines = [character(len=200) :: lines, '', 'wrote '//join_path(dir, 'report.md')//', '// &
               'regions.csv, effects.csv, residuals.csv'//trim(merge(', *.png', '       ', plotted))]
   end subroutine diagnose_command

   !> Self-check of the diagnosis on synthetic data with each effect injected
   subroutine selfcheck_command(path, out_dir, lines, error)
      character(len=*), intent(in) :: path, out_dir
      character(len=200), allocatable, intent(out) :: lines(:)
      type(error_type), allocatable, intent(out) :: error
      type(run_config) :: cfg
      type(diagnose_options) :: opts
      type(selfcheck_result) :: sc
      character(len=:), allocatable :: deck, dir
      dir = out_dir
      if (len(dir) == 0) dir = 'selfcheck'
      deck = path
      if (len(deck) == 0) then
         ! The built-in matrix, written out so that it can be edited and run again
         call make_dir(dir, error)
         if (allocated(error)) return
         deck = join_path(dir, 'selfcheck.nml')
         call write_lines(deck, selfcheck_deck(), error)
         if (allocated(error)) return
      end if
      call read_config_as(deck, '', dir, cfg, error)
      if (allocated(error)) return
      call diagnose_options_of(cfg, opts, error)
      if (allocated(error)) return
      call selfcheck_run(cfg, opts, sc, error)
      if (allocated(error)) return
      lines = selfcheck_report(sc)
      call make_dir(cfg%out_dir, error)
      if (allocated(error)) return
      call write_lines(join_path(cfg%out_dir, 'selfcheck.md'), lines, error)
   end subroutine selfcheck_command

   !> regions.csv, effects.csv, residuals.csv
   subroutine write_tables(dir, res, error)
      character(len=*), intent(in) :: dir
      type(diagnose_result), intent(in) :: res
      type(error_type), allocatable, intent(out) :: error
      character(len=200), allocatable :: rows(:)
      integer :: i, j, lead
      allocate (rows(0))
      rows = [character(len=200) :: rows, 'test,region,points,objective,noise_part,structured_gap,rms,bias,runs_z,structured']
      do i = 1, size(res%regions)
         associate (r => res%regions(i))
            rows = [character(len=200) :: rows, trim(r%test)//','//trim(r%label)//','//str(r%n)//','// &
               real_str(r%ssr, 'es12.5')//','//real_str(r%noise, 'es12.5')//','//real_str(r%gap, 'es12.5')// &
               ','//real_str(r%rms, 'es12.5')//','//real_str(r%bias, 'es12.5')//','//real_str(r%z, 'f0.2')// &
               ','//trim(merge('yes', 'no ', r%structured))]
         end associate
      end do
      call write_lines(join_path(dir, 'regions.csv'), rows, error)
      if (allocated(error)) return
      deallocate (rows)
      allocate (rows(0))
      rows = [character(len=200) :: rows, 'rank,effect,parameters,predicted_fall,predicted_dbic,refitted,'// &
              'objective_after,daic,dbic,gap_removed_fit,gap_removed_held_out,confirmed']
      do j = 1, size(res%effects)
         associate (e => res%effects(j))
            rows = [character(len=200) :: rows, str(j)//','//trim(e%name)//','//str(e%q)//','// &
               real_str(e%pred_drop, 'es12.5')//','//real_str(e%pred_dbic, 'f0.2')//','// &
               trim(merge('yes', 'no ', e%refitted))//','//real_str(e%f_after, 'es12.5')//','// &
               real_str(e%daic, 'f0.2')//','//real_str(e%dbic, 'f0.2')//','// &
               real_str(e%shrink_fit, 'f0.4')//','//real_str(e%shrink_held, 'f0.4')//','// &
               trim(merge('yes', 'no ', e%confirmed))]
         end associate
      end do
      call write_lines(join_path(dir, 'effects.csv'), rows, error)
      if (allocated(error)) return
      deallocate (rows)
      ! The curves: data, baseline, and with the leading (else the first refitted) effect
      lead = res%leading
      if (lead == 0) then
         do j = size(res%effects), 1, -1
            if (res%effects(j)%refitted) lead = j
         end do
      end if
      allocate (rows(size(res%t) + 1))
      rows(1) = 'test,held_out,t_s,class,data,baseline,with_effect,class_id'
      do i = 1, size(res%t)
         rows(i + 1) = trim(res%names(res%test_of(i)))//','// &
            trim(merge('yes', 'no ', res%held(res%test_of(i))))//','//real_str(res%t(i), 'es14.7')//','// &
            trim(class_names(res%cls(i)))//','//real_str(res%y_ex(i), 'es14.7')//','// &
            real_str(res%y_base(i), 'es14.7')//','//real_str(effect_curve(i), 'es14.7')//','// &
            str(res%cls(i))
      end do
      call write_lines(join_path(dir, 'residuals.csv'), rows, error)
   contains
      real(dp) function effect_curve(i) result(y)
         integer, intent(in) :: i
         y = res%y_base(i)
         if (lead > 0) y = res%effects(lead)%y(i)
      end function effect_curve
   end subroutine write_tables

   !> residuals.png (data - baseline against time, one panel per test) and fit.png (data,
   !> baseline and with the leading effect) with gnuplot; plotted false if it could not
   subroutine draw_plots(dir, res, plotted)
      character(len=*), intent(in) :: dir
      type(diagnose_result), intent(in) :: res
      logical, intent(out) :: plotted
      character(len=512), allocatable :: gp(:)
      type(error_type), allocatable :: error
      integer :: stat, cmdstat, i, nt
      nt = size(res%names)
      allocate (gp(0))
      gp = [character(len=512) :: gp, "set datafile separator ','", &
            "set linetype 1 lc rgb '#c03030'", "set linetype 2 lc rgb '#3050c0'", &
            "set linetype 3 lc rgb '#30a040'", "set linetype 4 lc rgb 'black'", 'set terminal pngcairo size 1200,'// &
            str(300*nt)//' font ",9"', "set output '"//join_path(dir, 'residuals.png')//"'", &
            'set multiplot layout '//str(nt)//',1', 'set key off', 'set xlabel "time (s)"']
      do i = 1, nt
         gp = [character(len=512) :: gp, 'set title "'//trim(res%names(i))//': data - baseline fit, '// &
               trim(res%unit(i))//'; red loading, blue unloading, green reversal, black hold"', &
               "plot '"//join_path(dir, 'residuals.csv')//"' every ::1 using 3:(strcol(1) eq '"// &
               trim(res%names(i))//"' ? $5-$6 : 1/0):8 with points pt 7 ps 0.3 lc variable"]
      end do
      gp = [character(len=512) :: gp, 'unset multiplot', "set output '"//join_path(dir, 'fit.png')//"'", &
            'set multiplot layout '//str(nt)//',1', 'set key top right']
      do i = 1, nt
         gp = [character(len=512) :: gp, 'set title "'//trim(res%names(i))//'"', &
               "plot '"//join_path(dir, 'residuals.csv')//"' every ::1 using 3:(strcol(1) eq '"// &
               trim(res%names(i))//"' ? $5 : 1/0) with dots lc rgb 'black' title 'data', '' every ::1 "// &
               "using 3:(strcol(1) eq '"//trim(res%names(i))//"' ? $6 : 1/0) with lines lc rgb 'blue' "// &
               "title 'baseline', '' every ::1 using 3:(strcol(1) eq '"//trim(res%names(i))// &
               "' ? $7 : 1/0) with lines lc rgb 'red' title 'with effect'"]
      end do
      gp = [character(len=512) :: gp, 'unset multiplot']
      call write_lines(join_path(dir, 'plots.gp'), gp, error)
      plotted = .false.
      if (allocated(error)) return
      call execute_command_line('gnuplot '//join_path(dir, 'plots.gp')//' > /dev/null 2>&1', &
                                exitstat=stat, cmdstat=cmdstat)
      plotted = cmdstat == 0 .and. stat == 0
   end subroutine draw_plots
end module usharp_cmd_diagnose
