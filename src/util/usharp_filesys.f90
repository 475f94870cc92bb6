!> File-system helpers through the C library (no shell involved)
module usharp_filesys
   use, intrinsic :: iso_c_binding, only: c_int, c_char, c_null_char, c_ptr, c_null_ptr, &
                                          c_associated, c_size_t, c_f_pointer, c_loc
   use usharp_kinds, only: dp
   use, intrinsic :: iso_fortran_env, only: int64
   use usharp_error, only: error_type, fatal_error, stat_io
   use usharp_process, only: run_process, process_result
   implicit none
   private

   public :: make_dir, join_path, file_exists, absolute_path, remove_file, remove_dir
   public :: rename_file, lock_file, unlock_file, file_hash, hash_text, hash_hex
   public :: raw_file, read_line, read_whole_file, standard_output, check_text

   !> A file written through the C library, every write and the close checked. (gfortran's
   !> formatted and stream writes do not report a full disk: the bytes are lost and iostat
   !> stays 0; write(2) reports it.) Lines are written as they come, unbuffered.
   type :: raw_file
      integer(c_int) :: fd = -1
      character(len=:), allocatable :: path
   contains
      procedure :: create => raw_create
      procedure :: put => raw_put
      procedure :: put_reals => raw_put_reals
      procedure :: sync => raw_sync
      procedure :: close => raw_close
   end type raw_file

   interface
      function c_mkdir(path, mode) bind(C, name='mkdir') result(stat)
         import :: c_int, c_char
         character(kind=c_char), intent(in) :: path(*)
         integer(c_int), value, intent(in) :: mode
         integer(c_int) :: stat
      end function c_mkdir
      function c_realpath(path, resolved) bind(C, name='realpath') result(res)
         import :: c_char, c_ptr
         character(kind=c_char), intent(in) :: path(*)
         character(kind=c_char), intent(out) :: resolved(*)
         type(c_ptr) :: res
      end function c_realpath
      function c_remove(path) bind(C, name='remove') result(stat)
         import :: c_int, c_char
         character(kind=c_char), intent(in) :: path(*)
         integer(c_int) :: stat
      end function c_remove
      function c_rename(old, new) bind(C, name='rename') result(stat)
         import :: c_int, c_char
         character(kind=c_char), intent(in) :: old(*), new(*)
         integer(c_int) :: stat
      end function c_rename
      function c_open(path, flags, mode) bind(C, name='open') result(fd)
         import :: c_int, c_char
         character(kind=c_char), intent(in) :: path(*)
         integer(c_int), value, intent(in) :: flags, mode
         integer(c_int) :: fd
      end function c_open
      function c_close(fd) bind(C, name='close') result(stat)
         import :: c_int
         integer(c_int), value, intent(in) :: fd
         integer(c_int) :: stat
      end function c_close
      function c_flock(fd, op) bind(C, name='flock') result(stat)
         import :: c_int
         integer(c_int), value, intent(in) :: fd, op
         integer(c_int) :: stat
      end function c_flock
      function c_write(fd, buf, count) bind(C, name='write') result(written)
         import :: c_int, c_char, c_size_t
         integer(c_int), value, intent(in) :: fd
         character(kind=c_char), intent(in) :: buf(*)
         integer(c_size_t), value, intent(in) :: count
         integer(c_size_t) :: written
      end function c_write
      function c_fsync(fd) bind(C, name='fsync') result(stat)
         import :: c_int
         integer(c_int), value, intent(in) :: fd
         integer(c_int) :: stat
      end function c_fsync
      function c_errno_location() bind(C, name='__errno_location') result(p)
         import :: c_ptr
         type(c_ptr) :: p
      end function c_errno_location
      function c_strerror(errnum) bind(C, name='strerror') result(p)
         import :: c_int, c_ptr
         integer(c_int), value, intent(in) :: errnum
         type(c_ptr) :: p
      end function c_strerror
   end interface

   ! Linux values of <fcntl.h> and <sys/file.h>
   integer(c_int), parameter :: o_wronly = 1, o_trunc = int(o'1000', c_int)
   integer(c_int), parameter :: o_rdwr = 2, o_creat = int(o'100', c_int), o_cloexec = int(o'2000000', c_int)
   integer(c_int), parameter :: lock_ex = 2, lock_nb = 4

   !> FNV-1a 64-bit offset basis 0xcbf29ce484222325 (as a signed 64-bit integer)
   integer(int64), parameter :: fnv_basis = -3750763034362895579_int64


contains

   !> The process's standard output as a raw_file: each put one write(2), its failure (a full
   !> disk, a closed pipe) an error, which the Fortran runtime's buffered unit does not report
   function standard_output() result(f)
      type(raw_file) :: f
      f%fd = 1_c_int
      f%path = 'standard output'
   end function standard_output

   !> Create (or truncate) a file for writing
   subroutine raw_create(self, path, error)
      class(raw_file), intent(inout) :: self
      character(len=*), intent(in) :: path
      type(error_type), allocatable, intent(out) :: error
      self%path = path
      self%fd = c_open(path//c_null_char, ior(ior(ior(o_wronly, o_creat), o_trunc), o_cloexec), &
                       int(o'644', c_int))
      if (self%fd < 0) call fatal_error(error, path//': cannot write ('//errno_text()//')', stat_io)
   end subroutine raw_create

   !> Write text (bytes as they are; add new_line('a') for a line)
   subroutine raw_put(self, text, error)
      class(raw_file), intent(inout) :: self
      character(len=*), intent(in) :: text
      type(error_type), allocatable, intent(out) :: error
      call write_all(self, text, len(text), error)
   end subroutine raw_put

   !> Write the bytes of doubles as they are in memory (binary files; no copy through a
   !> character buffer, which for the residual vectors of a fit costs more than the write)
   subroutine raw_put_reals(self, v, error)
      class(raw_file), intent(inout) :: self
      real(dp), intent(in), target :: v(:)
      type(error_type), allocatable, intent(out) :: error
      character(kind=c_char), pointer :: bytes(:)
      real(dp), allocatable, target :: packed(:)
      if (size(v) == 0) return
      if (is_contiguous(v)) then
         call c_f_pointer(c_loc(v(1)), bytes, [storage_size(v)/8*size(v)])
      else
         packed = v
         call c_f_pointer(c_loc(packed(1)), bytes, [storage_size(v)/8*size(v)])
      end if
      call write_all(self, bytes, size(bytes), error)
   end subroutine raw_put_reals

   !> Write n bytes, as many write(2) calls as it takes; a failure is an error naming the file
   subroutine write_all(self, buf, n, error)
      class(raw_file), intent(inout) :: self
      character(kind=c_char), intent(in) :: buf(*)
      integer, intent(in) :: n
      type(error_type), allocatable, intent(out) :: error
      integer(c_size_t) :: got
      integer :: done
      if (self%fd < 0) then
         call fatal_error(error, self%path//': write failed (not open)', stat_io)
         return
      end if
      done = 0
      do while (done < n)
         got = c_write(self%fd, buf(done + 1:n), int(n - done, c_size_t))
         if (got <= 0) then
            call fatal_error(error, self%path//': write failed ('//errno_text()//')', stat_io)
            return
         end if
         done = done + int(got)
      end do
   end subroutine write_all

   !> Wait until the file's contents are on the disk
   subroutine raw_sync(self, error)
      class(raw_file), intent(inout) :: self
      type(error_type), allocatable, intent(out) :: error
      if (self%fd < 0) return
      if (c_fsync(self%fd) /= 0) call fatal_error(error, self%path//': write failed ('// &
                                                  errno_text()//')', stat_io)
   end subroutine raw_sync

   !> Close the file (error, when given, reports a failure)
   subroutine raw_close(self, error)
      class(raw_file), intent(inout) :: self
      type(error_type), allocatable, intent(out), optional :: error
      integer(c_int) :: stat
      if (self%fd < 0) return
      stat = c_close(self%fd)
      self%fd = -1
      if (stat /= 0 .and. present(error)) call fatal_error(error, self%path// &
         ': write failed on close ('//errno_text()//')', stat_io)
   end subroutine raw_close

   !> The C library's text for the current errno
   function errno_text() result(text)
      character(len=:), allocatable :: text
      integer(c_int), pointer :: errno
      character(kind=c_char), pointer :: chars(:)
      integer :: k
      call c_f_pointer(c_errno_location(), errno)
      call c_f_pointer(c_strerror(errno), chars, [256])
      text = ''
      do k = 1, 256
         if (chars(k) == c_null_char) exit
         text = text//chars(k)
      end do
   end function errno_text

   !> Rename a file (atomic within one file system: a reader sees the old or the new file)
   subroutine rename_file(old, new, error)
      character(len=*), intent(in) :: old, new
      type(error_type), allocatable, intent(out) :: error
      if (c_rename(old//c_null_char, new//c_null_char) /= 0) &
         call fatal_error(error, new//': cannot move the finished file into place from '//old// &
                          ' ('//errno_text()//')', stat_io)
   end subroutine rename_file

   !> Take an advisory lock (flock) on the file path, created if needed, without waiting.
   !> fd is the open descriptor that holds the lock (-1 when taken by another process); the
   !> kernel releases it when the descriptor is closed or the process ends in any way, so a
   !> killed process leaves no stale lock. The descriptor is not inherited by commands run.
   subroutine lock_file(path, fd, error)
      character(len=*), intent(in) :: path
      integer, intent(out) :: fd
      type(error_type), allocatable, intent(out) :: error
      integer(c_int) :: cfd, stat
      fd = -1
      cfd = c_open(path//c_null_char, ior(ior(o_rdwr, o_creat), o_cloexec), int(o'644', c_int))
      if (cfd < 0) then
         call fatal_error(error, path//': cannot create the lock file', stat_io)
         return
      end if
      stat = c_flock(cfd, ior(lock_ex, lock_nb))
      if (stat /= 0) then
         stat = c_close(cfd)
         return
      end if
      fd = int(cfd)
   end subroutine lock_file

   !> Release a lock taken by lock_file
   subroutine unlock_file(fd)
      integer, intent(inout) :: fd
      integer(c_int) :: stat
      if (fd >= 0) stat = c_close(int(fd, c_int))
      fd = -1
   end subroutine unlock_file

   !> A file's bytes as one string (stream access: one read, not a formatted read per line)
   subroutine read_whole_file(path, text, error)
      !> the file
      character(len=*), intent(in) :: path
      !> its contents, line ends included
      character(len=:), allocatable, intent(out) :: text
      !> 'cannot open' or 'cannot read', naming the file
      type(error_type), allocatable, intent(out) :: error
      integer :: unit, ios
      integer(int64) :: nbytes
      character(len=512) :: msg
      open (newunit=unit, file=path, status='old', action='read', access='stream', &
            form='unformatted', iostat=ios, iomsg=msg)
      if (ios /= 0) then
         call fatal_error(error, path//': cannot open ('//trim(msg)//')')
         return
      end if
      inquire (unit=unit, size=nbytes)
      allocate (character(len=max(nbytes, 0_int64)) :: text)
      if (nbytes > 0) read (unit, iostat=ios, iomsg=msg) text
      close (unit)
      if (ios /= 0 .or. nbytes < 0) call fatal_error(error, path//': cannot read ('//trim(msg)//')')
   end subroutine read_whole_file

   !> A file read as text (an input deck, a data table) that is none: NUL bytes (UTF-16, a
   !> spreadsheet's binary file) or line ends of CR alone, which the readers would take for
   !> one long line; the error names the file and what to do
   pure subroutine check_text(path, text, error)
      !> the file
      character(len=*), intent(in) :: path
      !> its contents
      character(len=*), intent(in) :: text
      type(error_type), allocatable, intent(out) :: error
      if (index(text, achar(0)) > 0) then
         if (len(text) >= 2) then
            if (text(1:2) == achar(255)//achar(254) .or. text(1:2) == achar(254)//achar(255)) then
               call fatal_error(error, path//': the file is in UTF-16; save it as UTF-8 or ASCII')
               return
            end if
         end if
         call fatal_error(error, path//': holds NUL bytes, not text (UTF-16, or a binary file '// &
            'such as a spreadsheet workbook); save it as UTF-8 or ASCII text')
      else if (index(text, achar(13)) > 0 .and. index(text, achar(10)) == 0) then
         call fatal_error(error, path//': its lines end in a carriage return alone; save it '// &
            'with LF (or CR LF) line ends')
      end if
   end subroutine check_text

   !> FNV-1a 64-bit hash of a file's bytes; ok false if it cannot be read
   subroutine file_hash(path, hash, ok)
      character(len=*), intent(in) :: path
      integer(int64), intent(out) :: hash
      logical, intent(out) :: ok
      character(len=:), allocatable :: bytes
      type(error_type), allocatable :: error
      hash = 0
      call read_whole_file(path, bytes, error)
      ok = .not. allocated(error)
      if (ok) hash = hash_text(bytes)
   end subroutine file_hash

   !> FNV-1a 64-bit hash of a text. The product modulo 2**64 is formed on 32-bit halves, so
   !> no signed integer overflows (prime = 2**40 + 435)
   pure function hash_text(text) result(hash)
      character(len=*), intent(in) :: text
      integer(int64) :: hash
      integer(int64), parameter :: m32 = 4294967295_int64
      integer(int64) :: hi, lo, t
      integer :: k
      hi = iand(ishft(fnv_basis, -32), m32)
      lo = iand(fnv_basis, m32)
      do k = 1, len(text)
         lo = ieor(lo, int(iachar(text(k:k)), int64))
         t = lo*435_int64
         hi = iand(hi*435_int64 + ishft(t, -32) + iand(ishft(lo, 8), m32), m32)
         lo = iand(t, m32)
      end do
      hash = ior(ishft(hi, 32), lo)
   end function hash_text

   !> A hash as 16 hexadecimal digits
   pure function hash_hex(hash) result(hex)
      integer(int64), intent(in) :: hash
      character(len=16) :: hex
      write (hex, '(z16.16)') hash
   end function hash_hex

   !> Create a folder and its parents (like mkdir -p); an error if it cannot be made or written
   subroutine make_dir(path, error)
      character(len=*), intent(in) :: path
      type(error_type), allocatable, intent(out) :: error
      integer :: k, stat
      type(raw_file) :: probe
      logical :: gone
      character(len=:), allocatable :: why
      integer(c_int), pointer :: errno
      integer(c_int), parameter :: eexist = 17
      why = ''
      do k = 2, len_trim(path) + 1
         if (k <= len_trim(path)) then
            if (path(k:k) /= '/') cycle
         end if
         stat = c_mkdir(path(:k - 1)//c_null_char, int(o'755', c_int))
         if (stat /= 0) then
            ! The first folder that could not be made, and why (not that it is there
            ! already): the probe below would only find the output folder missing
            call c_f_pointer(c_errno_location(), errno)
            if (errno /= eexist .and. len(why) == 0) why = path(:k - 1)//': '//errno_text()
         end if
      end do
      ! Prove the folder is writable by creating and deleting a file in it (the C library's
      ! reason when not: "Not a directory", "File name too long", ...)
      call probe%create(join_path(path, '.usharp-write-test'), error)
      if (allocated(error)) then
         if (len(why) > 0 .and. index(error%message, '(No such file or directory)') > 0) then
            error%message = path//': output folder cannot be created or written ('//why//')'
         else
            error%message = path//': output folder cannot be created or written ('// &
               reason(error%message)//')'
         end if
         return
      end if
      call probe%close()
      gone = remove_file(join_path(path, '.usharp-write-test'))
   contains
      !> The text in the last parentheses of a message
      pure function reason(message) result(text)
         character(len=*), intent(in) :: message
         character(len=:), allocatable :: text
         integer :: i
         i = index(message, '(', back=.true.)
         text = message(i + 1:len(message) - 1)
      end function reason
   end subroutine make_dir

   !> 1 where join_path puts a '/' after dir, else 0
   pure integer function separator_width(dir) result(w)
      character(len=*), intent(in) :: dir
      w = 1
      if (len(dir) == 0) then
         w = 0
      else if (dir(len(dir):len(dir)) == '/') then
         w = 0
      end if
   end function separator_width

   !> dir/name
   pure function join_path(dir, name) result(path)
      character(len=*), intent(in) :: dir, name
      ! A length of its own, not deferred (see usharp_strings: threads call this at once)
      character(len=len(dir) + len(name) + separator_width(dir)) :: path
      if (separator_width(dir) == 0) then
         path = dir//name
      else
         path = dir//'/'//name
      end if
   end function join_path

   !> The absolute path of an existing file or folder ('' if it does not exist)
   function absolute_path(path) result(abs_path)
      character(len=*), intent(in) :: path
      character(len=:), allocatable :: abs_path
      character(kind=c_char) :: buf(4097)
      integer :: k
      abs_path = ''
      buf = c_null_char
      if (.not. c_associated(c_realpath(trim(path)//c_null_char, buf))) return
      do k = 1, size(buf)
         if (buf(k) == c_null_char) exit
         abs_path = abs_path//buf(k)
      end do
   end function absolute_path

   !> Remove a file or an empty folder; .true. when it is gone
   logical function remove_file(path) result(ok)
      character(len=*), intent(in) :: path
      logical :: exists
      ok = c_remove(path//c_null_char) == 0
      if (.not. ok) then
         inquire (file=path, exist=exists)
         ok = .not. exists
      end if
   end function remove_file

   !> Remove a folder with the files named in it; whatever else is there is removed by rm -r
   subroutine remove_dir(path, names)
      character(len=*), intent(in) :: path
      character(len=*), intent(in) :: names(:)
      integer :: k
      logical :: gone
      type(process_result) :: res
      character(len=:), allocatable :: argv(:)
      do k = 1, size(names)
         gone = remove_file(join_path(path, trim(names(k))))
      end do
      if (c_remove(path//c_null_char) == 0) return
      allocate (character(len=max(7, len(path))) :: argv(4))
      argv(1) = '/bin/rm'
      argv(2) = '-rf'
      argv(3) = '--'
      argv(4) = path
      call run_process(argv, '/', '/dev/null', '/dev/null', 600.0d0, 5.0d0, res, stoppable=.false.)
   end subroutine remove_dir

   !> Whether a file exists
   logical function file_exists(path)
      character(len=*), intent(in) :: path
      inquire (file=path, exist=file_exists)
   end function file_exists
   !> One line of any length from a formatted unit (without its end); ios 0, or the end of file
   subroutine read_line(unit, line, ios)
      integer, intent(in) :: unit
      character(len=:), allocatable, intent(out) :: line
      integer, intent(out) :: ios
      character(len=4096) :: buf
      integer :: nread
      line = ''
      do
         read (unit, '(a)', advance='no', iostat=ios, size=nread) buf
         line = line//buf(:nread)
         if (ios /= 0) exit
      end do
      if (is_iostat_eor(ios)) ios = 0
   end subroutine read_line

end module usharp_filesys
