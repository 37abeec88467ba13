//! The SUNDIALS context (`SUNContext`), created first and freed last, and — on SUNDIALS 7 —
//! the context-wide error handler and warning log.

use super::ffi;

/// Owns a `SUNContext`. Everything created with it must be freed before it (the solver types
/// guarantee this by field order).
#[derive(Debug)]
pub(crate) struct Context {
    raw: ffi::SUNContext,
}

impl Context {
    /// Creates a serial context (no MPI communicator; MPI is never initialised).
    pub(crate) fn new() -> Option<Self> {
        let mut raw: ffi::SUNContext = std::ptr::null_mut();
        // SAFETY: SUNContext_Create writes a new context into `raw`. SUNDIALS 6 takes a `void*`
        // communicator, null for serial use; SUNDIALS 7 takes a SUNComm, and SUN_COMM_NULL
        // (MPI_COMM_NULL in an MPI build: a null pointer would be taken for a real communicator
        // and duplicated, aborting before MPI_Init) is read from the headers by the C shim.
        #[cfg(not(sundials7))]
        let flag = unsafe { ffi::SUNContext_Create(std::ptr::null_mut(), &mut raw) };
        // SAFETY: as above; the shim only returns a constant.
        #[cfg(sundials7)]
        let flag = unsafe { ffi::SUNContext_Create(ffi::stickslip_sun_comm_null(), &mut raw) };
        if flag != 0 || raw.is_null() {
            return None;
        }
        Some(Self { raw })
    }

    pub(crate) fn raw(&self) -> ffi::SUNContext {
        self.raw
    }
}

#[cfg(sundials7)]
pub(crate) use v7::WarningLog;

#[cfg(sundials7)]
mod v7 {
    use super::super::callbacks::{error_handler, Diagnostics};
    use super::super::ffi;
    use super::Context;
    use std::ffi::{c_void, CString};
    use std::fs::File;
    use std::io::Read;
    use std::sync::atomic::{AtomicU64, Ordering};

    /// SUNDIALS 7 sends warnings ("t + h = t" among them) to the context's SUNLogger instead of
    /// the error handler. This points the logger's warning stream at a private, already
    /// unlinked file and reads what was written since the last look.
    #[derive(Debug)]
    pub(crate) struct WarningLog {
        logger: ffi::SUNLogger,
        file: File,
    }

    impl WarningLog {
        /// Flushes SUNDIALS' warning stream and returns the text written since the last call.
        pub(crate) fn take_new(&mut self) -> String {
            // SAFETY: the logger belongs to the context, which outlives this log (the solver
            // drops its callback data, which holds this log, before the context).
            unsafe { ffi::SUNLogger_Flush(self.logger, ffi::SUNLogLevel_SUN_LOGLEVEL_WARNING) };
            // One read(2) when nothing is new (read_to_string would add statx and lseek).
            let mut bytes = Vec::new();
            let mut chunk = [0u8; 4096];
            // A failed read ends this look; the next call resumes from the same offset.
            while let Ok(n @ 1..) = self.file.read(&mut chunk) {
                bytes.extend_from_slice(&chunk[..n]);
            }
            String::from_utf8_lossy(&bytes).into_owned()
        }
    }

    impl Context {
        /// Replaces SUNDIALS 7's default error handler (which logs) by one recording into
        /// `diag`. The handler lives for the context's lifetime; `diag` must too.
        pub(crate) fn capture_errors(&self, diag: *mut Diagnostics) -> std::ffi::c_int {
            // SAFETY: live context; `diag` points into the solver's boxed callback data, which
            // is freed only after the last SUNDIALS call on this context.
            unsafe {
                let flag = ffi::SUNContext_ClearErrHandlers(self.raw);
                if flag != 0 {
                    return flag;
                }
                ffi::SUNContext_PushErrHandler(self.raw, Some(error_handler), diag as *mut c_void)
            }
        }

        /// Directs the context logger's warnings to a new private file and returns its reader.
        pub(crate) fn warning_log(&self) -> std::io::Result<WarningLog> {
            static COUNTER: AtomicU64 = AtomicU64::new(0);
            let path = std::env::temp_dir().join(format!(
                "stickslip-sundials-warnings-{}-{}.log",
                std::process::id(),
                COUNTER.fetch_add(1, Ordering::Relaxed)
            ));
            let name = CString::new(path.as_os_str().as_encoded_bytes())
                .map_err(|e| std::io::Error::new(std::io::ErrorKind::InvalidInput, e))?;
            let mut logger: ffi::SUNLogger = std::ptr::null_mut();
            // SAFETY: live context; the getter writes the context's own logger pointer.
            let flag = unsafe { ffi::SUNContext_GetLogger(self.raw, &mut logger) };
            if flag != 0 || logger.is_null() {
                return Err(std::io::Error::other(format!("SUNContext_GetLogger failed ({flag})")));
            }
            // SAFETY: live logger; SUNDIALS opens (creates) the named file and copies the name.
            let flag = unsafe { ffi::SUNLogger_SetWarningFilename(logger, name.as_ptr()) };
            if flag != 0 {
                return Err(std::io::Error::other(format!(
                    "SUNLogger_SetWarningFilename({}) failed ({flag})",
                    path.display()
                )));
            }
            let file = File::open(&path);
            // Both descriptors stay valid after the name is gone; nothing is left behind.
            let _ = std::fs::remove_file(&path);
            Ok(WarningLog { logger, file: file? })
        }
    }
}

impl Drop for Context {
    fn drop(&mut self) {
        let mut raw = self.raw;
        // SAFETY: `raw` came from SUNContext_Create and is freed exactly once, here; owners
        // drop every object created with the context before the context itself.
        unsafe { ffi::SUNContext_Free(&mut raw) };
    }
}
