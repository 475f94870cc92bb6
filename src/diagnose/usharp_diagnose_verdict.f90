!> The verdict of a diagnosis: the leading confirmed effect and the words for it, each
!> refit's verdict, and the regions that carry the structured gap
module usharp_diagnose_verdict
   use usharp_kinds, only: dp
   use usharp_strings, only: real_str
   use usharp_sort, only: order_of
   use usharp_regions, only: region_stat
   use usharp_diagnose_types, only: diagnose_result, effect_outcome, fit_structured, held_quiet
   implicit none
   private

   public :: conclude, verdict_of, top_regions

contains

   !> The leading effect (confirmed, lowest BIC) and the verdict in words
   subroutine conclude(res)
      type(diagnose_result), intent(inout) :: res
      integer :: j, k
      integer, allocatable :: top(:)
      character(len=:), allocatable :: where
      res%leading = 0
      do j = 1, size(res%effects)
         if (.not. res%effects(j)%confirmed) cycle
         if (res%leading == 0) then
            res%leading = j
         else if (res%effects(j)%dbic < res%effects(res%leading)%dbic) then
            res%leading = j
         end if
      end do
      if (res%leading > 0) then
         associate (e => res%effects(res%leading))
            res%verdict = trim(e%name)//' explains the gap: BIC '//real_str(e%dbic, 'f0.1')// &
               ', structured gap removed '//real_str(100.0_dp*e%shrink_fit, 'f0.0')//' % on the fit tests'
            if (held_quiet(res)) then
               res%verdict = res%verdict//'; the held-out tests had none and still have none'
            else
               res%verdict = res%verdict//' and '//real_str(100.0_dp*e%shrink_held, 'f0.0')// &
                  ' % on the held-out tests'
            end if
         end associate
         return
      end if
      k = 0
      do j = 1, size(res%effects)
         if (res%effects(j)%significant) k = j
      end do
      if (.not. any(res%regions%structured)) then
         res%verdict = 'no significant effect: the residual is at the noise level'
         if (k > 0) res%verdict = res%verdict//' (refits that lower BIC do not carry to the held-out tests)'
         return
      end if
      where = ''
      top = top_regions(res%regions, size(res%regions))
      top = pack(top, res%regions(top)%structured)
      do j = 1, min(3, size(top))
         if (j > 1) where = where//'; '
         where = where//trim(res%regions(top(j))%test)//' '//trim(res%regions(top(j))%label)
      end do
      res%verdict = 'no catalogue effect is confirmed; the structured residual lies in: '//where
      do j = 1, size(res%effects)
         if (res%effects(j)%significant .and. .not. res%effects(j)%plausible) res%verdict = &
            res%verdict//'; '//trim(res%effects(j)%name)//' lowers BIC only at an implausible magnitude'

      end do
   end subroutine conclude

   !> Regions other than whole tests, by structured gap, largest first; at most nmax
   pure function top_regions(regs, nmax) result(idx)
      type(region_stat), intent(in) :: regs(:)
      integer, intent(in) :: nmax
      integer, allocatable :: idx(:)
      idx = order_of(-regs%gap)
      idx = pack(idx, regs(idx)%label /= 'whole test')
      idx = idx(1:min(nmax, size(idx)))
   end function top_regions

   pure function verdict_of(e, res) result(text)
      type(effect_outcome), intent(in) :: e
      type(diagnose_result), intent(in) :: res
      character(len=:), allocatable :: text
      if (e%confirmed) then
         text = 'confirmed'
      else if (e%significant .and. .not. e%plausible) then
         text = 'significant, but the magnitude is '//real_str(e%worst, 'f0.1')// &
                'x its physical limit: stands in for something else'
      else if (e%significant .and. .not. fit_structured(res) .and. held_quiet(res)) then
         text = 'significant, but no structured gap to explain'
      else if (e%significant) then
         text = 'significant, not confirmed on held-out'
      else
         text = 'not significant'
      end if
   end function verdict_of
end module usharp_diagnose_verdict
