!> A stop request by signal: SIGTERM (what a batch scheduler sends at its wall-time limit)
!> and SIGINT (Ctrl-C) set a flag that a fit checks between evaluations, so it stops with
!> its logs and journal complete and can be continued with --resume. SIGUSR1 is taken as a
!> SIGTERM: Open MPI's mpirun passes it on to every rank at once, while it holds a SIGTERM
!> back for its kill timeout (1 s) and kills the ranks one timeout later, too soon for them
!> to stop cleanly; so a job script stops MPI ranks with SIGUSR1.
!>
!> The flag is the one piece of global mutable state in usharp: a signal handler runs
!> outside any call chain and can hand nothing back but through a variable it can reach;
!> it only ever stores the signal's number (an async-signal-safe act) and is read in
!> between evaluations.
module usharp_signal
   use, intrinsic :: iso_c_binding, only: c_int, c_funptr, c_funloc, c_null_funptr
   implicit none
   private

   public :: catch_stop_signals, release_stop_signals, stop_signal, sigterm, sigint

   integer(c_int), parameter :: sigint = 2, sigterm = 15, sigusr1 = 10

   !> The number of the last stop signal received (0: none)
   integer(c_int), volatile, save :: received = 0

   interface
      function c_signal(signum, handler) bind(C, name='signal') result(previous)
         import :: c_int, c_funptr
         integer(c_int), value, intent(in) :: signum
         type(c_funptr), value, intent(in) :: handler
         type(c_funptr) :: previous
      end function c_signal
      function c_raise(signum) bind(C, name='raise') result(rc)
         import :: c_int
         integer(c_int), value, intent(in) :: signum
         integer(c_int) :: rc
      end function c_raise
   end interface

contains

   !> Catch SIGTERM, SIGINT and SIGUSR1 from now on (they no longer end the process at once)
   subroutine catch_stop_signals()
      type(c_funptr) :: previous
      previous = c_signal(sigterm, c_funloc(on_signal))
      previous = c_signal(sigint, c_funloc(on_signal))
      previous = c_signal(sigusr1, c_funloc(on_signal))
   end subroutine catch_stop_signals

   !> SIGTERM and SIGINT end the process again (SIG_DFL), e.g. once a fit is over, and SIGUSR1
   !> ends it as SIGTERM does (exit 128 + 15): a job script's stop that reaches the program
   !> outside a fit (reading its input, the identifiability report after it) ends it as the
   !> same stop within a fit does. Called once at the start of a command too.
   subroutine release_stop_signals()
      type(c_funptr) :: previous
      previous = c_signal(sigterm, c_null_funptr)
      previous = c_signal(sigint, c_null_funptr)
      previous = c_signal(sigusr1, c_funloc(end_as_term))
   end subroutine release_stop_signals

   !> The stop signal received since catch_stop_signals (0: none)
   integer function stop_signal()
      stop_signal = int(received)
   end function stop_signal

   !> SIGUSR1 outside a fit: SIGTERM raised with its default action (signal and raise are
   !> async-signal-safe)
   subroutine end_as_term(signum) bind(C)
      integer(c_int), value, intent(in) :: signum
      type(c_funptr) :: previous
      integer(c_int) :: rc
      previous = c_signal(sigterm, c_null_funptr)
      rc = c_raise(sigterm)
   end subroutine end_as_term

   subroutine on_signal(signum) bind(C)
      integer(c_int), value, intent(in) :: signum
      received = merge(sigterm, signum, signum == sigusr1)
   end subroutine on_signal
end module usharp_signal
