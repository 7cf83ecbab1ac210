"""Files written and checked as the CLI checks its outputs (volume/core/written_file.h): a writer can meet a
full disk and still report success (VTK's XML writers lose their last buffer on close), so each file is
read back before it counts: gzip to its end (CRCs and lengths), VTK XML ending with </VTKFile>, at least
its expected size, then flushed to the disk (fsync). A failure is WriteFailure "NAME: cannot write
(REASON)", NAME being the file as the user will know it (its final path, not the staging one)."""
import errno
import gzip
import os
import resource
import zlib

VTK_XML_TAIL = b"</VTKFile>\n"
VTK_XML_EXTENSIONS = (".vtu", ".vtp", ".vti", ".vts", ".vtr", ".pvd")
STORAGE_ERRORS = (errno.ENOSPC, errno.EDQUOT, errno.EFBIG, errno.EIO, errno.EROFS)
TELLING_ERRORS = STORAGE_ERRORS + (errno.EACCES, errno.EPERM, errno.ENOENT, errno.ENOTDIR, errno.ENAMETOOLONG,
                                   errno.EMFILE, errno.ENFILE, errno.ENOMEM)


class WriteFailure(RuntimeError):
    def __init__(self, name, reason):
        super().__init__(f"{name}: cannot write ({reason})")
        self.reason = reason


def _error_text(err):
    text = os.strerror(err)
    return text[:1].lower() + text[1:]


def failure_reason(path, err=0):
    """Why writing `path` failed: the error a write left, else what the file system says (no space left,
    the file-size limit reached), else "the file is incomplete"."""
    if err in TELLING_ERRORS:
        return _error_text(err)
    try:
        if os.statvfs(os.path.dirname(path) or ".").f_bavail == 0:
            return _error_text(errno.ENOSPC)
    except OSError:
        pass
    limit = resource.getrlimit(resource.RLIMIT_FSIZE)[0]
    if limit != resource.RLIM_INFINITY and os.path.exists(path) and os.path.getsize(path) >= limit:
        return _error_text(errno.EFBIG)
    return "the file is incomplete"


def _sync(path, folder=False):
    fd = os.open(path, os.O_RDONLY | (os.O_DIRECTORY if folder else 0))
    try:
        os.fsync(fd)
    except OSError as e:
        if e.errno != errno.EINVAL:  # a file system without fsync
            raise
    finally:
        os.close(fd)


def _gzip_length(path):
    """Decompressed length of a gzip file read to its end; raises on a cut or corrupted stream."""
    total = 0
    with gzip.open(path, "rb") as f:
        while chunk := f.read(1 << 20):
            total += len(chunk)
    return total


def _ends_with(path, tail):
    with open(path, "rb") as f:
        f.seek(0, os.SEEK_END)
        if f.tell() < len(tail):
            return False
        f.seek(-len(tail), os.SEEK_END)
        return f.read() == tail


def check_written(path, name=None, min_bytes=1):
    """Requires the file complete by its format (gzip, VTK XML) and at least `min_bytes` long, and
    flushes it to the disk; a folder (a writer's companion files) is checked file by file."""
    name = name or path
    try:
        if os.path.isdir(path):
            for entry in sorted(os.listdir(path)):
                check_written(os.path.join(path, entry), os.path.join(name, entry))
            _sync(path, folder=True)
            return
        _sync(path)
        complete = os.path.getsize(path) >= min_bytes
        if complete and path.endswith(".gz"):
            complete = _gzip_length(path) > 0
        if complete and path.endswith(VTK_XML_EXTENSIONS):
            complete = _ends_with(path, VTK_XML_TAIL)
    except (OSError, EOFError, zlib.error) as e:  # gzip.BadGzipFile is an OSError
        raise WriteFailure(name, failure_reason(path, getattr(e, "errno", 0) or 0)) from None
    if not complete:
        raise WriteFailure(name, failure_reason(path))


def write_text(path, text, name=None):
    """Writes the text (UTF-8) and checks it reached the disk whole."""
    data = text.encode("utf-8")
    try:
        with open(path, "wb") as f:
            f.write(data)
    except OSError as e:
        raise WriteFailure(name or path, failure_reason(path, e.errno or 0)) from None
    check_written(path, name, len(data))


def sync_folder(path):
    """Flushes a folder's entries (the files created or renamed in it) to the disk."""
    try:
        _sync(path, folder=True)
    except OSError as e:
        raise WriteFailure(path, failure_reason(path, e.errno or 0)) from None
