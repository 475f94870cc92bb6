!> The &model group (the model's name, material, temperature, elastic constants, stress unit)
!> and the &constants group (the model's constants, by their names).
module usharp_input_model
   use usharp_kinds, only: dp
   use usharp_error, only: error_type, fatal_error
   use usharp_strings, only: lower, str, real_str
   use usharp_model, only: model_type
   use usharp_model_registry, only: new_model, default_model
   use usharp_units, only: stress_factor
   use usharp_namelist, only: nml_file, group_text, find_group, group_error, read_error, check_length, &
                              value_len, unset
   implicit none
   private

   public :: read_model_group, read_constants_group, write_model_defaults, write_constants_defaults

   !> Plausible Young's moduli of metals at the temperature of any test, ksi and MPa: a value
   !> outside is another unit (GPa, psi) rather than a material
   real(dp), parameter :: youngs_ksi(2) = [1.0e3_dp, 1.0e5_dp], youngs_mpa(2) = [1.0e4_dp, 7.0e5_dp]
   !> Below a tenth of the melting temperature no metal is viscoplastic: the temperature was
   !> given in Celsius (room temperature 20 reads as 20 K)
   real(dp), parameter :: lowest_homologous = 0.1_dp
   !> The stress unit by default
   character(len=*), parameter :: default_units = 'ksi'
   !> Defaults of the settings of the D0 formula (the Miller model's own)
   real(dp), parameter :: default_d0 = 0.0_dp, default_d0_rate = 5.0e-5_dp, default_poisson = 0.3_dp

   !> The &model variables as given
   type :: model_values
      character(len=value_len) :: name, units
      real(dp) :: temperature, tm, youngs, poisson, d0, d0_yield, d0_rate, activation, tref
   end type model_values

contains

   !> Read &model into a new model of the name it gives (temperature, elastic and the model's
   !> own settings) and model_units (ksi or MPa)
   subroutine read_model_group(file, model, model_units, error)
      type(nml_file), intent(in) :: file
      class(model_type), allocatable, intent(out) :: model
      character(len=:), allocatable, intent(out) :: model_units
      type(error_type), allocatable, intent(out) :: error
      type(model_values) :: v
      integer :: ios, k
      character(len=512) :: msg
      character(len=:), allocatable :: lines(:)
      character(len=:), allocatable :: where
      k = find_group(file, 'model')
      if (k == 0) then
         call fatal_error(error, file%path//': group &model is missing')
         return
      end if
      call group_text(file, k, lines)
      call model_namelist(v, ios, msg, text=lines)
      if (ios /= 0) then
         call read_error(error, file, k, 'model', ios, msg, reread)
         return
      end if
      where = file%path//': &model: '
      call check_length(error, where, 'name', v%name)
      call check_length(error, where, 'units', v%units)
      if (allocated(error)) return
      call new_model(v%name, model, error)
      if (allocated(error)) then
         msg = error%message
         call fatal_error(error, where//trim(msg))
         return
      end if
      model_units = lower(trim(v%units))
      if (model_units == 'mpa') model_units = 'MPa'
      if (model_units /= 'ksi' .and. model_units /= 'MPa') then
         call fatal_error(error, where//"units = '"//trim(v%units)//"' is not known (ksi or MPa)")
         return
      end if
      if (required(v%temperature, 'temperature')) return
      if (required(v%tm, 'tm')) return
      if (required(v%youngs, 'youngs')) return
      call check_plausible(where, model_units, v%temperature, v%tm, v%youngs, error)
      if (allocated(error)) return
      model%temperature = v%temperature
      model%tm = v%tm
      model%youngs = v%youngs
      model%poisson = v%poisson
      call model%set_units(model_units)
      ! The model's own settings, where given
      if (v%d0 /= default_d0) call model%set_option('d0', v%d0, error)
      if (.not. allocated(error) .and. v%d0_yield /= unset) &
         call model%set_option('d0_yield', v%d0_yield, error)
      if (.not. allocated(error) .and. v%d0_rate /= default_d0_rate) &
         call model%set_option('d0_rate', v%d0_rate, error)
      ! An activation energy: the constants hold at tref, by default the &model temperature
      if (.not. allocated(error) .and. v%activation /= 0.0_dp) &
         call model%set_option('activation', v%activation, error)
      if (.not. allocated(error) .and. (v%activation /= 0.0_dp .or. v%tref /= 0.0_dp)) &
         call model%set_option('tref', merge(v%tref, v%temperature, v%tref /= 0.0_dp), error)
      if (allocated(error)) then
         msg = error%message
         call fatal_error(error, where//trim(msg))
      end if
   contains
      subroutine reread(lines, ios, msg)
         character(len=*), intent(in) :: lines(:)
         integer, intent(out) :: ios
         character(len=*), intent(out) :: msg
         type(model_values) :: scratch
         call model_namelist(scratch, ios, msg, text=lines)
      end subroutine reread

      logical function required(val, var) result(missing)
         real(dp), intent(in) :: val
         character(len=*), intent(in) :: var
         missing = val == unset
         if (missing) call fatal_error(error, where//var//' is not set')
      end function required
   end subroutine read_model_group

   !> Write &model with its starting values (unset reals: -huge) to unit
   subroutine write_model_defaults(unit)
      integer, intent(in) :: unit
      type(model_values) :: v
      integer :: ios
      character(len=512) :: msg
      call model_namelist(v, ios, msg, unit=unit)
   end subroutine write_model_defaults

   !> The &model namelist (temperature, tm and youngs must be given; d0_yield unset is the
   !> model's default in its unit): read from text or written to unit
   subroutine model_namelist(v, ios, msg, text, unit)
      type(model_values), intent(out) :: v
      integer, intent(out) :: ios
      character(len=*), intent(out) :: msg
      character(len=*), intent(in), optional :: text(:)
      integer, intent(in), optional :: unit
      character(len=value_len) :: name, units
      real(dp) :: temperature, tm, youngs, poisson, d0, d0_yield, d0_rate, activation, tref
      namelist /model/ name, units, temperature, tm, youngs, poisson, d0, d0_yield, d0_rate, &
         activation, tref
      name = default_model
      units = default_units
      temperature = unset
      tm = unset
      youngs = unset
      poisson = default_poisson
      d0 = default_d0
      d0_yield = unset
      d0_rate = default_d0_rate
      activation = 0.0_dp
      tref = 0.0_dp
      ios = 0
      msg = ''
      if (present(text)) read (text, nml=model, iostat=ios, iomsg=msg)
      if (present(unit)) write (unit, nml=model, iostat=ios, iomsg=msg)
      v = model_values(name, units, temperature, tm, youngs, poisson, d0, d0_yield, d0_rate, &
                       activation, tref)
   end subroutine model_namelist

   !> Values no metal test has are a wrong unit: temperatures are in K, youngs in the model's
   !> stress unit
   pure subroutine check_plausible(where, units, temperature, tm, youngs, error)
      character(len=*), intent(in) :: where, units
      real(dp), intent(in) :: temperature, tm, youngs
      type(error_type), allocatable, intent(out) :: error
      real(dp) :: range(2)
      if (.not. (tm > 0.0_dp)) then
         call fatal_error(error, where//'tm = '//str(tm)//': the melting temperature is in K, > 0')
      else if (.not. (temperature > 0.0_dp .and. temperature < tm)) then
         call fatal_error(error, where//'temperature = '//str(temperature)// &
            ' K: must lie between 0.1 tm and the melting temperature tm = '//str(tm)//' K')
      else if (temperature < lowest_homologous*tm) then
         call fatal_error(error, where//'temperature = '//str(temperature)//' K is below a tenth '// &
            'of tm = '//str(tm)//' K, where no metal is viscoplastic: temperature is in kelvin '// &
            '(K = Celsius + 273.15)')
      end if
      if (allocated(error)) return
      range = merge(youngs_ksi, youngs_mpa, units == 'ksi')
      if (.not. (youngs >= range(1) .and. youngs <= range(2))) then
         call fatal_error(error, where//'youngs = '//str(youngs)//' '//units// &
            " is no metal's Young's modulus ("//real_str(range(1), 'es7.1')//' to '// &
            real_str(range(2), 'es7.1')//' '// &
            units//'): youngs is in the model stress unit, '//units// &
            trim(merge(' (1 GPa = 145.04 ksi)', ' (1 GPa = 1000 MPa)  ', units == 'ksi')))
      end if
   end subroutine check_plausible

   !> Read &constants into the model's constants; every constant must be given
   subroutine read_constants_group(file, model, error)
      type(nml_file), intent(in) :: file
      class(model_type), intent(inout) :: model
      type(error_type), allocatable, intent(out) :: error
      integer :: ios, k, i
      character(len=512) :: msg
      character(len=:), allocatable :: lines(:)
      character(len=:), allocatable :: missing
      k = find_group(file, 'constants')
      if (k == 0) then
         call fatal_error(error, file%path//': group &constants is missing')
         return
      end if
      call group_text(file, k, lines)
      call model%constants_namelist(unset, ios, msg, text=lines)
      if (ios /= 0) then
         call read_error(error, file, k, 'constants', ios, msg, reread)
         return
      end if
      missing = ''
      do i = 1, model%n_constants()
         if (model%get_constant(i) == unset) missing = missing//' '//lower(model%constant_name(i))
      end do
      if (len(missing) > 0) then
         call group_error(error, file%path, 'constants', 'every constant must be set '// &
            '(missing: '//trim(adjustl(missing))//')')
         return
      end if
   contains
      subroutine reread(lines, ios, msg)
         character(len=*), intent(in) :: lines(:)
         integer, intent(out) :: ios
         character(len=*), intent(out) :: msg
         class(model_type), allocatable :: scratch
         allocate (scratch, source=model)
         call scratch%constants_namelist(unset, ios, msg, text=lines)
      end subroutine reread
   end subroutine read_constants_group

   !> Write &constants of the model (no defaults: every constant is unset, -huge) to unit
   subroutine write_constants_defaults(model, unit)
      class(model_type), intent(in) :: model
      integer, intent(in) :: unit
      class(model_type), allocatable :: blank
      integer :: ios, i
      character(len=512) :: msg
      allocate (blank, source=model)
      do i = 1, blank%n_constants()
         call blank%set_constant(i, unset)
      end do
      call blank%constants_namelist(unset, ios, msg, unit=unit)
   end subroutine write_constants_defaults

end module usharp_input_model
