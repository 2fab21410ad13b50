//! What weft tells a person about the graphics driver the window draws
//! with, when that driver is known to misbehave.
//!
//! On a machine without a GPU the window draws with Mesa's software Vulkan
//! driver, lavapipe. Mesa 22.3's (Debian 12's `mesa-vulkan-drivers`) leaks
//! small mappings for every frame drawn: the window's resident memory
//! grows by about 20 MB a second while playing, outside anything weft or
//! the viewer holds; Mesa 25.0's does not (docs/debugger.md, "Memory while
//! playing"). A person who sees the memory climb should hear it from weft
//! at start, not find it in a profiler.

use eframe::wgpu::{AdapterInfo, Backend};

/// The first Mesa release whose lavapipe was measured not to leak.
const MESA_FIXED: u32 = 25;

/// A warning for the adapter the window draws with, if it is a driver known
/// (or, for the releases between, suspected) to leak while playing.
pub fn warning(info: &AdapterInfo) -> Option<String> {
    leak_warning(info.backend, &info.name, &info.driver_info)
}

/// [`warning`] from the adapter's backend, its name (`llvmpipe (…)` for
/// lavapipe) and its driver's version string (`Mesa 22.3.6`).
fn leak_warning(backend: Backend, name: &str, driver_info: &str) -> Option<String> {
    if backend != Backend::Vulkan || !name.starts_with("llvmpipe") {
        return None;
    }
    let version = driver_info.strip_prefix("Mesa ")?;
    let major: u32 = version.split('.').next()?.parse().ok()?;
    if major >= MESA_FIXED {
        return None;
    }
    let version = version.split_whitespace().next().unwrap_or(version);
    let leaks = if major <= 22 {
        "leaks"
    } else {
        "may leak (Mesa 22.3's does)"
    };
    Some(format!(
        "the window draws with lavapipe, Mesa {version}'s software Vulkan driver, which {leaks} \
         memory for every frame drawn: about 20 MB a second while playing. Mesa {MESA_FIXED} \
         does not (on Debian 12: apt-get install -t bookworm-backports mesa-vulkan-drivers); \
         see docs/debugger.md, \"Memory while playing\""
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    const LAVAPIPE: &str = "llvmpipe (LLVM 15.0.6, 256 bits)";

    #[test]
    fn warns_of_mesa_22_lavapipe() {
        let w = leak_warning(Backend::Vulkan, LAVAPIPE, "Mesa 22.3.6").expect("a warning");
        assert!(
            w.contains("Mesa 22.3.6's software Vulkan driver, which leaks"),
            "{w}"
        );
        assert!(w.contains("bookworm-backports"), "{w}");
    }

    #[test]
    fn says_a_release_between_may_leak() {
        let w = leak_warning(Backend::Vulkan, LAVAPIPE, "Mesa 24.0.5-1ubuntu1").expect("a warning");
        assert!(w.contains("Mesa 24.0.5-1ubuntu1's"), "{w}");
        assert!(w.contains("may leak"), "{w}");
    }

    #[test]
    fn is_quiet_for_a_fixed_mesa_a_gpu_or_another_backend() {
        assert_eq!(
            leak_warning(Backend::Vulkan, LAVAPIPE, "Mesa 25.0.7-1~bpo12+1"),
            None
        );
        assert_eq!(
            leak_warning(
                Backend::Vulkan,
                "AMD Radeon RX 6600 (RADV NAVI23)",
                "Mesa 22.3.6"
            ),
            None
        );
        assert_eq!(leak_warning(Backend::Gl, LAVAPIPE, "Mesa 22.3.6"), None);
        assert_eq!(
            leak_warning(Backend::Vulkan, LAVAPIPE, "something else"),
            None
        );
    }
}
