//! Intel Open Image Denoise's `RT` filter on the HDR render with the albedo and normal guides,
//! through the C API of the `oidn` crate (`oidn::sys`), on OIDN's CPU device with images shared
//! with pathwave's own buffers (no copies into OIDN buffers). By default the guides are first
//! denoised by OIDN's own filters (its recommendation for guides that are not noise-free: the
//! render's guides are means over its own camera rays, noisy where a pixel holds sub-pixel
//! detail, a lens or motion) and emitters seen directly are kept out of the filter ([`Options`]).
//!
//! The C API rather than the crate's `RayTracing` wrapper: prefiltering a guide runs the filter
//! with that guide as its only input (`albedo` or `normal`, no `color`), which the wrapper cannot
//! express, and the wrapper's `clean_aux` sets a parameter named `clean_aux` where OIDN reads
//! `cleanAux` (OIDN 2.5.1 warns "unknown filter parameter" and keeps the default).

#![expect(unsafe_code, reason = "calls into Open Image Denoise's C API")]

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

/// OIDN's `quality`: which size of network runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Quality {
    /// OIDN's default.
    High,
    /// Smaller networks, faster.
    Balanced,
    /// The smallest.
    Fast,
}

impl Quality {
    fn raw(self) -> i32 {
        (match self {
            Self::High => sys::OIDNQuality_OIDN_QUALITY_HIGH,
            Self::Balanced => sys::OIDNQuality_OIDN_QUALITY_BALANCED,
            Self::Fast => sys::OIDNQuality_OIDN_QUALITY_FAST,
        }) as i32
    }
}

/// Filter settings. The defaults, measured at 16 spp on cornell-diffuse, cornell, spheres-sky,
/// mesh and cornell-smoke (benches/results/denoiser.md): prefiltered guides cut relMSE against the
/// guides as rendered by 20-25% on spheres-sky and cornell-smoke (and 7% on cornell, whose mean
/// moves -0.3% instead of -0.7%), and cost 4-8% on cornell-diffuse and mesh; prefilters of
/// balanced quality (OIDN's standard networks, where high quality runs its large ones) give the
/// same figures within 2% in 60% of the time. Taking out the emitters seen directly cuts relMSE
/// by 19-38% where an area light is in view (and RMSE by 40%: OIDN otherwise reshapes the light
/// and its edge) and changes nothing under a sky.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Options {
    /// The quality of the filter on the render.
    pub quality: Quality,
    /// The quality of the filters on the guides (with [`Aux::Prefiltered`]).
    pub prefilter_quality: Quality,
    /// Guide with the albedo.
    pub albedo: bool,
    /// Guide with the normal too (OIDN takes a normal only beside an albedo).
    pub normal: bool,
    /// How the guides are given.
    pub aux: Aux,
    /// Take the radiance of emitting surfaces seen directly (the guides' `emission`, exact) out of
    /// the render before filtering and add it back after, where a pixel's camera rays all met
    /// surfaces facing one way; the background stays in (OIDN is trained with skies in view).
    pub emitters: bool,
    /// OIDN's worker threads, 0 for all cores.
    pub threads: usize,
}

impl Default for Options {
    fn default() -> Self {
        Self {
            quality: Quality::High,
            prefilter_quality: Quality::Balanced,
            albedo: true,
            normal: true,
            aux: Aux::Prefiltered,
            emitters: true,
            threads: 0,
        }
    }
}

/// An OIDN CPU device, committed.
struct Device {
    raw: sys::OIDNDevice,
    threads: usize,
}

// SAFETY: OIDN's API calls are thread-safe; the device is used under the lock of `DEVICE` only.
unsafe impl Send for Device {}

impl Drop for Device {
    fn drop(&mut self) {
        // SAFETY: `raw` is a device `oidnNewDevice` returned (not null), released once, here.
        unsafe { sys::oidnReleaseDevice(self.raw) };
    }
}

/// One device for the process (its creation starts OIDN's thread pool), remade when the number
/// of threads asked for changes.
static DEVICE: Mutex<Option<Device>> = Mutex::new(None);

/// The error OIDN recorded on `device` (null: errors of device creation), if any.
fn error(device: sys::OIDNDevice) -> Option<String> {
    let mut msg: *const c_char = std::ptr::null();
    // SAFETY: `device` is a live device or null (which OIDN documents as the errors of device
    // creation); `msg` is a valid place for the message's pointer.
    let code = unsafe { sys::oidnGetDeviceError(device, &mut msg) };
    (code != sys::OIDNError_OIDN_ERROR_NONE).then(|| match msg.is_null() {
        true => format!("error code {code}"),
        // SAFETY: OIDN set `msg` to a NUL-terminated string that stays valid until the next
        // call on the device; it is copied before any.
        false => unsafe { CStr::from_ptr(msg) }.to_string_lossy().into_owned(),
    })
}

impl Device {
    fn new(threads: usize) -> Result<Self, String> {
        // SAFETY: a plain call with a valid device type; a null result is checked below.
        let raw = unsafe { sys::oidnNewDevice(sys::OIDNDeviceType_OIDN_DEVICE_TYPE_CPU) };
        if raw.is_null() {
            return Err(format!(
                "Open Image Denoise has no CPU device: {} (its libOpenImageDenoise_device_cpu and libtbb \
                 must lie beside libOpenImageDenoise; scripts/setup-oidn.sh installs them)",
                error(std::ptr::null_mut()).unwrap_or_else(|| "no error given".into())
            ));
        }
        let device = Self { raw, threads };
        // SAFETY: `raw` is the live device just made; the parameter name is a NUL-terminated
        // literal.
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
        // SAFETY: `self.0` is a filter `oidnNewFilter` returned (not null), released once, here.
        unsafe { sys::oidnReleaseFilter(self.0) };
    }
}

impl Filter {
    fn new(device: &Device) -> Result<Self, String> {
        // SAFETY: `device.raw` is a live, committed device; the type is a NUL-terminated literal.
        // A null result is checked below.
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
        // SAFETY: `pixels` holds `width * height` FLOAT3 pixels (checked above) and OIDN reads or
        // writes them only in `run`, which `denoise` calls while every shared buffer is still
        // borrowed there; the filter is dropped before the buffers.
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
        // SAFETY: `self.0` is a live filter; `name` is NUL-terminated.
        unsafe { sys::oidnSetFilterBool(self.0, name.as_ptr(), value) };
    }

    fn quality(&self, q: Quality) {
        // SAFETY: `self.0` is a live filter; the name is a NUL-terminated literal.
        unsafe { sys::oidnSetFilterInt(self.0, c"quality".as_ptr(), q.raw()) };
    }

    fn run(&self, device: &Device, what: &str) -> Result<(), String> {
        // SAFETY: `self.0` is a live filter whose shared images are still alive (see `image`).
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

/// The process's device for `threads` threads, made now if it is not there (the lock holds
/// `Some`).
fn device(threads: usize) -> Result<std::sync::MutexGuard<'static, Option<Device>>, String> {
    let mut lock = DEVICE.lock().unwrap_or_else(|p| p.into_inner());
    if lock.as_ref().is_none_or(|d| d.threads != threads) {
        *lock = None;
        *lock = Some(Device::new(threads)?);
    }
    Ok(lock)
}

/// Makes the CPU device now (kept for the denoising to come): a library without its CPU device
/// fails here, before a render, rather than after it.
pub fn ready(threads: usize) -> Result<(), String> {
    device(threads).map(drop)
}

/// Denoises the HDR image `color` (per-pixel means, linear) with the guides `aovs`.
pub fn denoise(color: &[Vec3], aovs: &Aovs, o: &Options) -> Result<Vec<Vec3>, String> {
    let _span = tracing::info_span!("oidn", width = aovs.width, height = aovs.height).entered();
    let (w, h) = (aovs.width as usize, aovs.height as usize);
    assert!(color.len() == w * h && aovs.albedo.len() == w * h && aovs.normal.len() == w * h);
    let lock = device(o.threads)?;
    let device = lock.as_ref().expect("made by device()");
    // The guides, owned: prefiltering denoises them in place.
    let mut albedo = o.albedo.then(|| aovs.albedo.clone());
    let mut normal = (o.albedo && o.normal).then(|| aovs.normal.clone());
    if o.aux == Aux::Prefiltered {
        for (name, guide) in [(c"albedo", &mut albedo), (c"normal", &mut normal)] {
            if let Some(g) = guide {
                let f = Filter::new(device)?;
                f.image(name, g, w, h);
                f.image(c"output", g, w, h);
                f.quality(o.prefilter_quality);
                f.run(device, &format!("prefiltering the {} guide", name.to_string_lossy()))?;
            }
        }
    }
    // A pixel whose camera rays met surfaces of one orientation has a unit normal guide; where
    // they also met the background, or surfaces turned other ways, the mean is shorter.
    let direct: Vec<Vec3> = match o.emitters {
        true => aovs
            .emission
            .iter()
            .zip(&aovs.normal)
            .map(|(e, n)| if n.length_squared() > 0.98 { *e } else { Vec3::ZERO })
            .collect(),
        false => vec![Vec3::ZERO; w * h],
    };
    // The rest of the pixel is >= 0 but for rounding.
    let mut input: Vec<Vec3> = color.iter().zip(&direct).map(|(c, e)| (*c - *e).max(Vec3::ZERO)).collect();
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
    f.quality(o.quality);
    f.flag(c"cleanAux", albedo.is_some() && o.aux != Aux::AsIs);
    f.run(device, "denoising the render")?;
    Ok(out.iter().zip(&direct).map(|(c, e)| *c + *e).collect())
}
