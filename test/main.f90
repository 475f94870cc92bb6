!> Runs every test suite and ends with the line 'N passed, M failed'
program tester
   use, intrinsic :: iso_fortran_env, only: output_unit
   use testdrive, only: error_type, unittest_type, testsuite_type, new_testsuite, skipped
   use test_model, only: collect_model
   use test_models, only: collect_models
   use test_history, only: collect_history
   use test_driver, only: collect_driver
   use test_input, only: collect_input
   use test_table, only: collect_table
   use test_fit, only: collect_fit
   use test_update, only: collect_update
   use test_upf, only: collect_upf
   use test_external, only: collect_external
   use test_optimise, only: collect_optimise
   use test_design, only: collect_design
   use test_diagnose, only: collect_diagnose
   use test_cli, only: collect_cli
   use test_safety, only: collect_safety
   use test_cluster, only: collect_cluster
   use test_diagnose_data, only: collect_diagnose_data
   use test_chaboche, only: collect_chaboche
   use test_tmf, only: collect_tmf
   use test_math, only: collect_math
   implicit none
   type(testsuite_type), allocatable :: suites(:)
   type(unittest_type), allocatable :: tests(:)
   type(error_type), allocatable :: error
   character(len=64) :: only, one
   integer :: is, it, npass, nfail, nskip

   suites = [ &
      new_testsuite('math', collect_math), &
      new_testsuite('model', collect_model), &
      new_testsuite('models', collect_models), &
      new_testsuite('tmf', collect_tmf), &
      new_testsuite('history', collect_history), &
      new_testsuite('driver', collect_driver), &
      new_testsuite('table', collect_table), &
      new_testsuite('input', collect_input), &
      new_testsuite('fit', collect_fit), &
      new_testsuite('update', collect_update), &
      new_testsuite('upf', collect_upf), &
      new_testsuite('external', collect_external), &
      new_testsuite('optimise', collect_optimise), &
      new_testsuite('design', collect_design), &
      new_testsuite('diagnose', collect_diagnose), &
      new_testsuite('cli', collect_cli), &
      new_testsuite('safety', collect_safety), &
      new_testsuite('cluster', collect_cluster), &
      new_testsuite('diagnose-data', collect_diagnose_data), &
      new_testsuite('chaboche', collect_chaboche)]
   ! An optional argument runs one suite only, a second one test of it
   only = ''
   one = ''
   if (command_argument_count() > 0) call get_command_argument(1, only)
   if (command_argument_count() > 1) call get_command_argument(2, one)
   npass = 0
   nfail = 0
   nskip = 0
   do is = 1, size(suites)
      if (len_trim(only) > 0 .and. suites(is)%name /= trim(only)) cycle
      write (output_unit, '(a)') '# suite '//suites(is)%name
      call suites(is)%collect(tests)
      do it = 1, size(tests)
         if (len_trim(one) > 0 .and. tests(it)%name /= trim(one)) cycle
         call tests(it)%test(error)
         if (.not. allocated(error)) then
            npass = npass + 1
            write (output_unit, '(2x,a)') 'ok    '//tests(it)%name
         else if (error%stat == skipped) then
            nskip = nskip + 1
            write (output_unit, '(2x,a)') 'SKIP  '//tests(it)%name//': '//error%message
         else
            nfail = nfail + 1
            write (output_unit, '(2x,a)') 'FAIL  '//tests(it)%name//': '//error%message
         end if
         flush (output_unit)
         if (allocated(error)) deallocate (error)
      end do
   end do
   write (output_unit, '(i0,a,i0,a,i0,a)') npass, ' passed, ', nfail, ' failed, ', nskip, ' skipped'
   if (nfail > 0) error stop 1
end program tester
