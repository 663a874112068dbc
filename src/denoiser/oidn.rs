//! Intel Open Image Denoise's `RT` filter on the HDR render with the albedo and normal guides,
//! through the C API of the `oidn` crate (`oidn::sys`), on OIDN's CPU device with images shared
//! with pathwave's own buffers (no copies into OIDN buffers).
//!
//! The C API rather than the crate's `RayTracing` wrapper: prefiltering a guide runs the filter
//! with that guide as its only input (`albedo` or `normal`, no `color`), which the wrapper cannot
//! express, and the wrapper's `clean_aux` sets a parameter named `clean_aux` where OIDN reads
//! `cleanAux` (OIDN 2.5.1 warns "unknown filter parameter" and keeps the default).

use crate::integrator::aov::Aovs;
use glam::Vec3;
use oidn::sys;
use std::ffi::{CStr, c_char};
use std::sync::Mutex;

/// How the guides reach the filter.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Aux {
    /// As rendered, to the weights OIDN trained on noisy guides (`cleanAux` off).
    AsIs,
    /// Each guide first denoised by OIDN's own filter, then given as clean (`cleanAux` on): what
    /// OIDN's documentation recommends for noisy guides.
    Prefiltered,
    /// As rendered, declared clean (`cleanAux` on).
    Clean,
}

/// Filter settings.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Options {
    /// Guide with the albedo.
    pub albedo: bool,
    /// Guide with the normal too (OIDN takes a normal only beside an albedo).
    pub normal: bool,
    /// How the guides are given.
    pub aux: Aux,
    /// OIDN's worker threads, 0 for all cores.
    pub threads: usize,
}

impl Default for Options {
    fn default() -> Self {
        Self { albedo: true, normal: true, aux: Aux::Prefiltered, threads: 0 }
    }
}

/// An OIDN CPU device, committed.
struct Device {
    raw: sys::OIDNDevice,
    threads: usize,
}

// OIDN's API calls are thread-safe; the device is used under the lock of `DEVICE` only.
unsafe impl Send for Device {}

impl Drop for Device {
    fn drop(&mut self) {
        unsafe { sys::oidnReleaseDevice(self.raw) };
    }
}

/// One device for the process (its creation starts OIDN's thread pool), remade when the number
/// of threads asked for changes.
static DEVICE: Mutex<Option<Device>> = Mutex::new(None);

/// The error OIDN recorded on `device` (null: errors of device creation), if any.
fn error(device: sys::OIDNDevice) -> Option<String> {
    let mut msg: *const c_char = std::ptr::null();
    let code = unsafe { sys::oidnGetDeviceError(device, &mut msg) };
    (code != sys::OIDNError_OIDN_ERROR_NONE).then(|| match msg.is_null() {
        true => format!("error code {code}"),
        false => unsafe { CStr::from_ptr(msg) }.to_string_lossy().into_owned(),
    })
}

impl Device {
    fn new(threads: usize) -> Result<Self, String> {
        let raw = unsafe { sys::oidnNewDevice(sys::OIDNDeviceType_OIDN_DEVICE_TYPE_CPU) };
        if raw.is_null() {
            return Err(format!(
                "Open Image Denoise has no CPU device: {} (its libOpenImageDenoise_device_cpu and libtbb \
                 must lie beside libOpenImageDenoise; scripts/setup-oidn.sh installs them)",
                error(std::ptr::null_mut()).unwrap_or_else(|| "no error given".into())
            ));
        }
        let device = Self { raw, threads };
        unsafe {
            if threads > 0 {
                sys::oidnSetDeviceInt(raw, c"numThreads".as_ptr(), threads.min(i32::MAX as usize) as i32);
            }
            sys::oidnCommitDevice(raw);
        }
        match error(raw) {
            Some(e) => Err(format!("Open Image Denoise: the CPU device: {e}")),
            None => Ok(device),
        }
    }
}

/// An RT filter on `device`, released on drop.
struct Filter(sys::OIDNFilter);

impl Drop for Filter {
    fn drop(&mut self) {
        unsafe { sys::oidnReleaseFilter(self.0) };
    }
}

impl Filter {
    fn new(device: &Device) -> Result<Self, String> {
        let raw = unsafe { sys::oidnNewFilter(device.raw, c"RT".as_ptr()) };
        match raw.is_null() {
            true => {
                Err(format!("Open Image Denoise: no RT filter: {}", error(device.raw).unwrap_or_default()))
            }
            false => Ok(Self(raw)),
        }
    }

    /// Shares `pixels` (RGB float triples, row-major) as the image `name`.
    fn image(&self, name: &CStr, pixels: &mut [Vec3], width: usize, height: usize) {
        assert_eq!(pixels.len(), width * height);
        // Vec3 is three f32s in a row (repr(C), 12 bytes): OIDN's FLOAT3 at its default strides.
        const { assert!(std::mem::size_of::<Vec3>() == 12) };
        unsafe {
            sys::oidnSetSharedFilterImage(
                self.0,
                name.as_ptr(),
                pixels.as_mut_ptr().cast(),
                sys::OIDNFormat_OIDN_FORMAT_FLOAT3,
                width,
                height,
                0,
                0,
                0,
            );
        }
    }

    fn flag(&self, name: &CStr, value: bool) {
        unsafe { sys::oidnSetFilterBool(self.0, name.as_ptr(), value) };
    }

    fn run(&self, device: &Device, what: &str) -> Result<(), String> {
        unsafe {
            sys::oidnCommitFilter(self.0);
            sys::oidnExecuteFilter(self.0);
        }
        match error(device.raw) {
            Some(e) => Err(format!("Open Image Denoise ({what}): {e}")),
            None => Ok(()),
        }
    }
}

/// Denoises the HDR image `color` (per-pixel means, linear) with the guides `aovs`.
pub fn denoise(color: &[Vec3], aovs: &Aovs, o: &Options) -> Result<Vec<Vec3>, String> {
    let _span = tracing::info_span!("oidn", width = aovs.width, height = aovs.height).entered();
    let (w, h) = (aovs.width as usize, aovs.height as usize);
    assert!(color.len() == w * h && aovs.albedo.len() == w * h && aovs.normal.len() == w * h);
    let mut lock = DEVICE.lock().unwrap_or_else(|p| p.into_inner());
    if lock.as_ref().is_none_or(|d| d.threads != o.threads) {
        *lock = None;
        *lock = Some(Device::new(o.threads)?);
    }
    let device = lock.as_ref().expect("made above");
    // The guides, owned: prefiltering denoises them in place.
    let mut albedo = o.albedo.then(|| aovs.albedo.clone());
    let mut normal = (o.albedo && o.normal).then(|| aovs.normal.clone());
    if o.aux == Aux::Prefiltered {
        for (name, guide) in [(c"albedo", &mut albedo), (c"normal", &mut normal)] {
            if let Some(g) = guide {
                let f = Filter::new(device)?;
                f.image(name, g, w, h);
                f.image(c"output", g, w, h);
                f.run(device, &format!("prefiltering the {} guide", name.to_string_lossy()))?;
            }
        }
    }
    let mut input = color.to_vec();
    let mut out = vec![Vec3::ZERO; w * h];
    let f = Filter::new(device)?;
    f.image(c"color", &mut input, w, h);
    if let Some(a) = &mut albedo {
        f.image(c"albedo", a, w, h);
    }
    if let Some(n) = &mut normal {
        f.image(c"normal", n, w, h);
    }
    f.image(c"output", &mut out, w, h);
    f.flag(c"hdr", true);
    f.flag(c"cleanAux", albedo.is_some() && o.aux != Aux::AsIs);
    f.run(device, "denoising the render")?;
    Ok(out)
}
