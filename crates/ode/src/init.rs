//! Process- and thread-level ODE set-up, and the lock that serialises the
//! parts of ODE that use global state.

use std::cell::Cell;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Mutex, MutexGuard, Once};

use crate::OdeError;

static INIT: Once = Once::new();
static INIT_OK: AtomicBool = AtomicBool::new(false);

/// Debian's libode is built without `ODE_EXT_mt_collisions`, and its random
/// generator (used by QuickStep to shuffle constraint rows) is one global
/// variable: collision and stepping of different worlds must not overlap.
static GLOBAL: Mutex<()> = Mutex::new(());

struct ThreadData {
    allocated: Cell<bool>,
}

impl Drop for ThreadData {
    fn drop(&mut self) {
        if self.allocated.get() {
            // SAFETY: this thread allocated ODE's per-thread data (flag set
            // only after dAllocateODEDataForThread succeeded) and is exiting;
            // ODE documents this call for exactly that moment.
            unsafe { ode_sys::dCleanupODEAllDataForThread() };
        }
    }
}

thread_local! {
    static THREAD: ThreadData = const { ThreadData { allocated: Cell::new(false) } };
}

/// Initialises the library once per process and ODE's per-thread data once
/// per calling thread. Cheap after the first call in a thread.
pub(crate) fn ensure_thread() -> Result<(), OdeError> {
    INIT.call_once(|| {
        // SAFETY: dInitODE2 takes no pointers; `Once` guarantees it runs once
        // per process, before any other ODE call made through this crate.
        let ok = unsafe { ode_sys::dInitODE2(0) } != 0;
        INIT_OK.store(ok, Ordering::Release);
    });
    if !INIT_OK.load(Ordering::Acquire) {
        return Err(OdeError::Ode("initialise the library (dInitODE2)"));
    }
    // `try_with`: a world kept in a thread-local may be dropped after this
    // thread's ODE data is gone (thread exit); the caller then leaks it
    // rather than panic in a destructor (found by the daemon_bytes fuzzer).
    let reached = THREAD.try_with(|t| {
        if t.allocated.get() {
            return Ok(());
        }
        // SAFETY: the library is initialised (checked above); the flag value
        // u32::MAX is dAllocateMaskAll (-1 as unsigned), "all kinds of data".
        let ok = unsafe { ode_sys::dAllocateODEDataForThread(u32::MAX) } != 0;
        if ok {
            t.allocated.set(true);
            Ok(())
        } else {
            Err(OdeError::Ode("allocate per-thread data"))
        }
    });
    reached.unwrap_or(Err(OdeError::Ode(
        "reach per-thread data (the thread is exiting)",
    )))
}

/// Held while ODE touches process-wide state (collision, stepping, the random
/// generator). A panic while holding it cannot leave `()` inconsistent, so a
/// poisoned lock is simply taken over.
pub(crate) fn global_lock() -> MutexGuard<'static, ()> {
    GLOBAL
        .lock()
        .unwrap_or_else(|poisoned| poisoned.into_inner())
}

/// Holds the process-wide lock until dropped, for a fork: a thread inside
/// ODE when the process forks would leave the lock held in the child for
/// ever (the child has no such thread), and every world there would wait.
pub fn hold_for_fork() -> MutexGuard<'static, ()> {
    global_lock()
}

/// Seeds ODE's process-wide random generator (`dRandSetSeed`).
///
/// A [`World`](crate::World) swaps in its own generator state around every
/// step (see [`World::set_rand_seed`](crate::World::set_rand_seed)), so this
/// only matters for ODE calls made outside a world step.
pub fn rand_set_seed(seed: u64) -> Result<(), OdeError> {
    ensure_thread()?;
    let _guard = global_lock();
    // SAFETY: plain store into ODE's generator state; serialised by the lock.
    unsafe { ode_sys::dRandSetSeed(seed as std::os::raw::c_ulong) };
    Ok(())
}

/// ODE's process-wide random generator state (`dRandGetSeed`).
pub(crate) fn rand_get_seed_locked(_guard: &MutexGuard<'static, ()>) -> u64 {
    // SAFETY: plain load of ODE's generator state; the caller holds the lock.
    unsafe { ode_sys::dRandGetSeed() as u64 }
}

pub(crate) fn rand_set_seed_locked(_guard: &MutexGuard<'static, ()>, seed: u64) {
    // SAFETY: plain store of ODE's generator state; the caller holds the lock.
    unsafe { ode_sys::dRandSetSeed(seed as std::os::raw::c_ulong) };
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_thread_gets_its_data() {
        ensure_thread().unwrap();
        let other = std::thread::spawn(|| {
            ensure_thread().unwrap();
            THREAD.with(|t| t.allocated.get())
        });
        assert!(other.join().unwrap());
    }

    /// Regression (fuzz target daemon_bytes, which keeps its world in a
    /// thread-local): a world dropped during thread exit, after ODE's
    /// per-thread data, panicked in a destructor and aborted the process.
    #[test]
    fn a_world_dropped_at_thread_exit_does_not_panic() {
        use std::cell::RefCell;
        thread_local! {
            static KEPT: RefCell<Option<crate::World>> = const { RefCell::new(None) };
        }
        let exited = std::thread::spawn(|| {
            // Registered before ODE's per-thread data, so destroyed after it.
            KEPT.with(|k| {
                *k.borrow_mut() = Some(
                    crate::World::new(crate::StepParams::gazebo(), crate::SpaceKind::Simple)
                        .unwrap(),
                );
            });
        })
        .join();
        assert!(exited.is_ok());
    }

    #[test]
    fn seed_round_trips() {
        ensure_thread().unwrap();
        let guard = global_lock();
        rand_set_seed_locked(&guard, 12345);
        assert_eq!(rand_get_seed_locked(&guard), 12345);
    }
}
