!> ANSYS APDL input decks for one test, as the original drove ANSYS: a unit-cube SOLID185 element
!> with symmetry planes x = 0, y = 0, z = 0, the Miller user material through TB,USER (the 13
!> properties in the order of usharp_upf) read from the constants file with *VREAD, TB,STATE
!> with the initial drag stress, TUNIF for the temperature, one load step per segment of the
!> same history the internal driver integrates, automatic time stepping with the namelist's
!> increments, and a POST26 PRVAR listing of time, axial stress and axial strain.
module usharp_apdl
   use usharp_kinds, only: dp
   use usharp_error, only: error_type, fatal_error, stat_input
   use usharp_simulation, only: solver_options
   use usharp_strings, only: str, real_str
   use usharp_config, only: run_config, test_config, test_increments
   use usharp_history, only: control_strain
   use usharp_external, only: n_constants_file
   use usharp_version, only: usharp_version_string
   implicit none
   private

   public :: apdl_deck, apdl_real, line_len, check_deckable

   !> Most time increments of one load step at the largest increment
   real(dp), parameter :: max_increments = 1.0e6_dp

   integer, parameter :: line_len = 160
   !> A history's start value away from 0 is put on over this share of its first segment
   real(dp), parameter :: jump_share = 1.0e-6_dp

contains

   !> A real as APDL reads it: the fewest digits that read back as the same double
   pure function apdl_real(x) result(text)
      real(dp), intent(in) :: x
      character(len=:), allocatable :: text
      character(len=32) :: buf
      real(dp) :: back
      integer :: d, ios
      do d = 1, 16
         write (buf, '(es32.'//str(d)//'e3)') x
         read (buf, *, iostat=ios) back
         if (ios == 0 .and. back == x) exit
      end do
      text = trim(adjustl(buf))
   end function apdl_real

   !> Whether a deck of test says what usharp simulates: refused, a temperature cycle (the
   !> deck is isothermal) and a load step that needs more than max_increments increments of
   !> the largest (a creep step of 1.4e7 s at 0.15 s: 9.4e7 increments, each written out)
   pure subroutine check_deckable(cfg, test, error)
      type(run_config), intent(in) :: cfg
      type(test_config), intent(in) :: test
      type(error_type), allocatable, intent(out) :: error
      type(solver_options) :: inc
      real(dp) :: most
      integer :: k
      if (allocated(test%hist%temp)) then
         call fatal_error(error, cfg%path//": test '"//test%name//"': its temperature cycle "// &
            '(tmf_temperatures) would be lost: usharp deck writes isothermal decks (one TBTEMP '// &
            'and TUNIF)', stat_input)
         return
      end if
      inc = test_increments(test, cfg%solver)
      do k = 2, size(test%hist%t)
         most = (test%hist%t(k) - test%hist%t(k - 1))/inc%dt_max
         if (most <= max_increments) cycle
         call fatal_error(error, cfg%path//": test '"//test%name//"': load step "//str(k - 1)// &
            ' lasts '//real_str(test%hist%t(k) - test%hist%t(k - 1), 'es9.2')//' s: at dt_max = '// &
            real_str(inc%dt_max, 'g0.3')//' s at least '//real_str(most, 'es8.1')//' increments, '// &
            'more than the '//str(nint(max_increments))//' a deck allows; give the &test '// &
            'its own dt_max (s)', stat_input)
         return
      end do
   end subroutine check_deckable

   !> The deck's lines for test of cfg; command is the usharp command that regenerates it
   subroutine apdl_deck(cfg, test, command, lines, error)
      type(run_config), intent(in) :: cfg
      type(test_config), intent(in) :: test
      character(len=*), intent(in) :: command
      character(len=line_len), allocatable, intent(out) :: lines(:)
      type(error_type), allocatable, intent(out) :: error
      integer :: n, k, np, j
      character(len=:), allocatable :: cname, cext, oname, oext, temp, names_text, row
      integer, allocatable :: spos(:)
      real(dp), allocatable :: sval(:)
      character(len=:), allocatable :: snames(:), snotes(:)
      real(dp) :: v, t0, v0, jump
      logical :: strain
      type(solver_options) :: inc

      inc = test_increments(test, cfg%solver)
      associate (h => test%hist, ext => test%ext)
         ! ANSYS starts at t = 0 unloaded: the history's times are taken from its start (a
         ! recording from t = 10 s, or cut from a longer test), and a start value that is not
         ! round-off of 0 (a measured strain starting at 3e-5) is a first load step within
         ! jump_share of the first segment, elastic as the internal driver's start is
         t0 = h%t(1)
         v0 = h%v(1)
         if (abs(v0) <= 1.0e-9_dp*maxval(abs(h%v))) v0 = 0.0_dp
         jump = 0.0_dp
         if (v0 /= 0.0_dp) jump = jump_share*(h%t(2) - t0)
         strain = h%control == control_strain
         call split_name(ext%constants_file, cname, cext)
         call split_name(ext%output_file, oname, oext)
         ! The test's own temperature, else the model's
         temp = apdl_real(merge(test%temperature, cfg%model%temperature, test%temperature > 0.0_dp))
         np = cfg%model%n_props()
         call cfg%model%fe_start_values(spos, sval, snames, snotes)
         names_text = cfg%model%prop_name(1)
         do j = 2, np
            names_text = names_text//', '//cfg%model%prop_name(j)
         end do
         do j = 1, size(spos)
            names_text = names_text//', '//trim(snames(j))
         end do
         allocate (lines(90 + 7*size(h%t)))
         n = 0
         call add('! usharp '//usharp_version_string//" APDL deck for test '"//test%name//"' of "// &
                  cfg%path)
         call add('! regenerate: '//command)
         row = '! history '//test%history_kind//', '//merge('strain', 'stress', strain)// &
               ' control, '//str(size(h%t) - 1)//' load steps, '//real_str(h%end_time() - t0, 'g0.8')//' s'
         if (t0 /= 0.0_dp) row = row//' (its times from its start, '//real_str(t0, 'g0.8')//' s)'
         call add(row)
         if (v0 /= 0.0_dp) call add('! load step 0 puts its start value '//apdl_real(v0)//' on within '// &
                                    apdl_real(jump)//' s, elastically, as usharp starts from it')
         call add('! units: stress '//cfg%units//' (E and the constants), time s, temperature K;')
         call add('! the cube has unit edges, so the top displacement is the axial strain.')
         call add('! needs an ANSYS linked with the usharp USERMAT (docs/guide/fe-users.md).')
         call add('! reads '//ext%constants_file//' ('//names_text//'), writes '//ext%output_file)
         call add('/BATCH')
         call add('/TITLE,usharp '//test%name)
         call add('/PREP7')
         call add('*DIM,props,ARRAY,'//str(n_constants_file(cfg%model)))
         call add('*VREAD,props(1),'//cname//','//cext//',,IJK,'//str(n_constants_file(cfg%model)))
         call add(ext%constants_format)
         call add('ET,1,SOLID185')
         call add('N,1,0,0,0')
         call add('N,2,1,0,0')
         call add('N,3,1,1,0')
         call add('N,4,0,1,0')
         call add('N,5,0,0,1')
         call add('N,6,1,0,1')
         call add('N,7,1,1,1')
         call add('N,8,0,1,1')
         call add('TYPE,1')
         call add('MAT,1')
         call add('E,1,2,3,4,5,6,7,8')
         call add('TB,USER,1,1,'//str(np))
         call add('TBTEMP,'//temp)
         ! Six values a TBDATA command
         do j = 1, np, 6
            row = 'TBDATA,'//str(j)
            do k = j, min(j + 5, np)
               row = row//',props('//str(k)//')'
            end do
            call add(row)
         end do
         call add('TB,STATE,1,,'//str(cfg%model%n_state()))
         do j = 1, size(spos)
            row = 'TBDATA,'//str(spos(j))//',props('//str(np + j)//')'
            call add(row//repeat(' ', max(1, 30 - len(row)))//'! '//trim(snotes(j)))
         end do
         call add('TUNIF,'//temp)
         call add('! symmetry planes x = 0, y = 0, z = 0')
         call add('D,1,UX,0')
         call add('D,4,UX,0')
         call add('D,5,UX,0')
         call add('D,8,UX,0')
         call add('D,1,UY,0')
         call add('D,2,UY,0')
         call add('D,5,UY,0')
         call add('D,6,UY,0')
         call add('D,1,UZ,0,,4,1')
         call add('FINISH')
         call add('/SOLU')
         call add('ANTYPE,STATIC')
         call add('NROPT,FULL')
         call add('AUTOTS,ON')
         call add('KBC,0')
         call add('OUTRES,ALL,ALL')
         if (v0 /= 0.0_dp) then
            call add('! load step 0')
            call add('TIME,'//apdl_real(jump))
            call add('DELTIM,'//apdl_real(jump)//','//apdl_real(min(inc%dt_min, jump))//','// &
                     apdl_real(jump))
            call load(v0)
            call add('SOLVE')
         end if
         do k = 2, size(h%t)
            v = h%v(k)
            call add('! load step '//str(k - 1))
            call add('TIME,'//apdl_real(h%t(k) - t0))
            call add('DELTIM,'//apdl_real(inc%dt_init)//','//apdl_real(inc%dt_min)// &
                     ','//apdl_real(inc%dt_max))
            call load(v)
            call add('SOLVE')
         end do
         call add('FINISH')
         call add('/POST26')
         call add('NUMVAR,10')
         call add('ESOL,2,1,7,S,Z,STRESS')
         call add('NSOL,3,7,U,Z,STRAIN')
         call add('/OUTPUT,'//oname//','//oext)
         call add('PRVAR,STRESS,STRAIN')
         call add('/OUTPUT')
         call add('FINISH')
      end associate
      lines = lines(:n)

   contains

      subroutine add(text)
         character(len=*), intent(in) :: text
         n = n + 1
         lines(n) = text
      end subroutine add

      !> The load at the end of a load step: the top's displacement (the strain) or force
      subroutine load(value)
         real(dp), intent(in) :: value
         if (strain) then
            call add('D,5,UZ,'//apdl_real(value)//',,8,1')
         else
            ! uniform traction on the unit top face: a quarter of the force at each node
            call add('F,5,FZ,'//apdl_real(0.25_dp*value)//',,8,1')
         end if
      end subroutine load
   end subroutine apdl_deck

   !> 'Constants.txt' -> 'Constants', 'txt' (APDL takes name and extension apart)
   pure subroutine split_name(file, name, ext)
      character(len=*), intent(in) :: file
      character(len=:), allocatable, intent(out) :: name, ext
      integer :: k
      k = index(file, '.', back=.true.)
      if (k == 0) then
         name = file
         ext = ''
      else
         name = file(:k - 1)
         ext = file(k + 1:)
      end if
   end subroutine split_name
end module usharp_apdl
