//! `--backend gles`: wgpu's GL backend on an OpenGL ES 3.x context that we make through EGL.
//!
//! wgpu's own EGL set-up (wgpu-hal 30, `src/gles/egl.rs`, `Inner::create`) asks for a desktop
//! OpenGL 3.3 core context whenever the display lists `OpenGL` among its client APIs, and falls
//! back to GLES only when that fails; no option forces GLES. NVIDIA's EGL lists OpenGL, so wgpu
//! gets GL 3.3 there, which has no compute shaders or storage buffers. GLES 3.1+ has both, so here
//! we create the display and a GLES context ourselves (as wgpu-hal does, surfaceless or on a 1×1
//! pbuffer) and hand it to wgpu through `hal::gles::Adapter::new_external`.
//!
//! An external adapter's context is never made current by wgpu (its `AdapterContext` has no
//! EGL handle): [`GlesContext::make_current`] must be called on the thread that then uses the
//! device, before `request_device`. mfx drives wgpu from one thread.

use std::ffi::c_void;
use std::sync::Arc;

use khronos_egl as egl;

type Egl = egl::DynamicInstance<egl::EGL1_4>;

/// `EGL_EXT_platform_device` (one display per GPU, no window system needed).
const EGL_PLATFORM_DEVICE_EXT: egl::Enum = 0x313F;
/// `EGL_MESA_platform_surfaceless` (Mesa without a window system: llvmpipe, or a DRM device).
const EGL_PLATFORM_SURFACELESS_MESA: egl::Enum = 0x31DD;

/// Why EGL gives no GLES 3 adapter, or why one display was passed over. `origin` names the
/// display (platform, device index).
#[derive(Debug, thiserror::Error)]
pub enum GlesError {
    /// The loader's message (its error type is libloading's, which khronos-egl does not export).
    #[error("cannot load libEGL.so.1: {0}")]
    LoadEgl(String),
    /// An EGL call failed on one display.
    #[error("{origin}: {call}: {error}")]
    Egl {
        origin: String,
        call: &'static str,
        error: egl::Error,
    },
    #[error("eglMakeCurrent ({origin}): {error}")]
    MakeCurrent { origin: String, error: egl::Error },
    #[error("{origin}: no EGL config renders GLES 3")]
    NoConfig { origin: String },
    /// No 3.2, 3.1 or 3.0 context; `last` is the error of the last one tried.
    #[error("{origin}: no GLES 3.x context ({})", .last.map_or("?".into(), |e| e.to_string()))]
    NoContext {
        origin: String,
        last: Option<egl::Error>,
    },
    #[error("{0}: wgpu does not accept the GLES context")]
    Refused(String),
    #[error("EGL offers no display")]
    NoDisplay,
    /// Every display tried, each with why it was passed over.
    #[error("no GLES 3 adapter through EGL: {}", .0.iter().map(|e| e.to_string()).collect::<Vec<_>>().join("; "))]
    NoAdapter(Vec<GlesError>),
}

/// One EGL display with a current-able GLES 3.x context. Kept alive as long as its adapter and
/// device (the `Gpu` holds it); dropping it destroys the context and terminates the display.
pub struct GlesContext {
    egl: Arc<Egl>,
    display: egl::Display,
    context: egl::Context,
    /// A 1×1 pbuffer where the display cannot make a context current without a surface.
    surface: Option<egl::Surface>,
    /// Which display this is (platform, device index), for messages.
    pub origin: String,
}

// The handles are plain pointers that EGL allows to use from any thread (one at a time).
unsafe impl Send for GlesContext {}
unsafe impl Sync for GlesContext {}

impl GlesContext {
    /// Makes this context current on the calling thread.
    pub fn make_current(&self) -> Result<(), GlesError> {
        self.egl
            .make_current(self.display, self.surface, self.surface, Some(self.context))
            .map_err(|error| GlesError::MakeCurrent {
                origin: self.origin.clone(),
                error,
            })
    }
}

impl Drop for GlesContext {
    fn drop(&mut self) {
        // Errors here leave nothing to undo: the process is done with this display. Release
        // only our own context: another adapter's may be the current one.
        if self.egl.get_current_context() == Some(self.context) {
            let _ = self.egl.make_current(self.display, None, None, None);
        }
        if let Some(s) = self.surface {
            let _ = self.egl.destroy_surface(self.display, s);
        }
        let _ = self.egl.destroy_context(self.display, self.context);
        let _ = self.egl.terminate(self.display);
    }
}

/// Every GLES adapter EGL offers, each with its context, in EGL's order; or why there is none
/// (no libEGL, no display, no GLES 3 context). The displays are tried by platform: one per
/// device (`EGL_EXT_platform_device`), else Mesa's surfaceless platform, else the default
/// display; the first platform that yields an adapter is used, and each display that failed is
/// named in the error when none did.
pub fn adapters(instance: &wgpu::Instance) -> Result<Vec<(wgpu::Adapter, GlesContext)>, GlesError> {
    let egl =
        Arc::new(unsafe { Egl::load_required() }.map_err(|e| GlesError::LoadEgl(e.to_string()))?);
    let mut why = Vec::new();
    for platform in platforms(&egl) {
        let mut out = Vec::new();
        for (display, origin) in platform {
            match open(&egl, display, origin.clone()).and_then(|ctx| {
                expose(instance, &egl, &ctx)
                    .map(|a| (a, ctx))
                    .ok_or_else(|| GlesError::Refused(origin.clone()))
            }) {
                Ok(pair) => out.push(pair),
                Err(e) => why.push(e),
            }
        }
        if !out.is_empty() {
            for e in why {
                log::info!("GLES display skipped: {e}");
            }
            return Ok(out);
        }
    }
    if why.is_empty() {
        why.push(GlesError::NoDisplay);
    }
    Err(GlesError::NoAdapter(why))
}

/// The displays to try, by platform in order of preference: one per device
/// (`EGL_EXT_platform_device`), Mesa's surfaceless platform, the default display.
fn platforms(egl: &Arc<Egl>) -> Vec<Vec<(egl::Display, String)>> {
    let client = egl
        .query_string(None, egl::EXTENSIONS)
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let has = |e: &str| client.split_whitespace().any(|x| x == e);
    let mut out = Vec::new();
    if let Some(egl15) = egl.upcast::<egl::EGL1_5>() {
        if has("EGL_EXT_platform_device") && has("EGL_EXT_device_enumeration") {
            let mut devices = Vec::new();
            for (i, dev) in query_devices(egl).into_iter().enumerate() {
                match unsafe {
                    egl15.get_platform_display(EGL_PLATFORM_DEVICE_EXT, dev, &[egl::ATTRIB_NONE])
                } {
                    Ok(d) => devices.push((d, format!("EGL device {i}"))),
                    Err(e) => log::info!("EGL device {i}: no display ({e})"),
                }
            }
            out.push(devices);
        }
        if has("EGL_MESA_platform_surfaceless") {
            match unsafe {
                egl15.get_platform_display(
                    EGL_PLATFORM_SURFACELESS_MESA,
                    egl::DEFAULT_DISPLAY,
                    &[egl::ATTRIB_NONE],
                )
            } {
                Ok(d) => out.push(vec![(d, "EGL surfaceless".to_string())]),
                Err(e) => log::info!("EGL surfaceless: no display ({e})"),
            }
        }
    }
    if let Some(d) = unsafe { egl.get_display(egl::DEFAULT_DISPLAY) } {
        out.push(vec![(d, "EGL default display".to_string())]);
    }
    out
}

/// `eglQueryDevicesEXT`, an extension entry point (looked up by name).
fn query_devices(egl: &Egl) -> Vec<*mut c_void> {
    type QueryDevices = unsafe extern "system" fn(i32, *mut *mut c_void, *mut i32) -> u32;
    let Some(f) = egl.get_proc_address("eglQueryDevicesEXT") else {
        return Vec::new();
    };
    let f: QueryDevices = unsafe { std::mem::transmute(f) };
    let mut n = 0i32;
    if unsafe { f(0, std::ptr::null_mut(), &mut n) } == 0 || n <= 0 {
        return Vec::new();
    }
    let mut devs = vec![std::ptr::null_mut(); n as usize];
    if unsafe { f(n, devs.as_mut_ptr(), &mut n) } == 0 {
        return Vec::new();
    }
    devs.truncate(n.max(0) as usize);
    devs
}

/// Initialises `display` and makes the newest GLES 3 context it offers (3.2, else 3.1, else
/// 3.0) current on this thread.
fn open(egl: &Arc<Egl>, display: egl::Display, origin: String) -> Result<GlesContext, GlesError> {
    let fail = |call: &'static str, error: egl::Error| GlesError::Egl {
        origin: origin.clone(),
        call,
        error,
    };
    egl.initialize(display)
        .map_err(|e| fail("eglInitialize", e))?;
    let exts = egl
        .query_string(Some(display), egl::EXTENSIONS)
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let has = |e: &str| exts.split_whitespace().any(|x| x == e);
    let surfaceless = has("EGL_KHR_surfaceless_context");
    let mut attribs = vec![egl::RENDERABLE_TYPE, egl::OPENGL_ES3_BIT];
    if !surfaceless {
        attribs.extend([egl::SURFACE_TYPE, egl::PBUFFER_BIT]);
    }
    attribs.push(egl::NONE);
    let config = match egl
        .choose_first_config(display, &attribs)
        .map_err(|e| fail("eglChooseConfig", e))?
    {
        Some(c) => c,
        // A context needs no config to render into its own framebuffers (as wgpu's do) where
        // the display has EGL_KHR_no_config_context; Mesa's device platform offers no config.
        None if surfaceless && has("EGL_KHR_no_config_context") => unsafe {
            egl::Config::from_ptr(std::ptr::null_mut())
        },
        None => return Err(GlesError::NoConfig { origin }),
    };
    egl.bind_api(egl::OPENGL_ES_API)
        .map_err(|e| fail("eglBindAPI(OPENGL_ES)", e))?;
    let mut context = None;
    let mut last = None;
    for minor in [2, 1, 0] {
        let a = [
            egl::CONTEXT_MAJOR_VERSION,
            3,
            egl::CONTEXT_MINOR_VERSION,
            minor,
            egl::NONE,
        ];
        match egl.create_context(display, config, None, &a) {
            Ok(c) => {
                context = Some(c);
                break;
            }
            Err(e) => last = Some(e),
        }
    }
    let context = context.ok_or_else(|| GlesError::NoContext {
        origin: origin.clone(),
        last,
    })?;
    let surface = if surfaceless {
        None
    } else {
        Some(
            egl.create_pbuffer_surface(
                display,
                config,
                &[egl::WIDTH, 1, egl::HEIGHT, 1, egl::NONE],
            )
            .map_err(|e| fail("eglCreatePbufferSurface", e))?,
        )
    };
    let ctx = GlesContext {
        egl: egl.clone(),
        display,
        context,
        surface,
        origin,
    };
    ctx.make_current()?;
    Ok(ctx)
}

/// Wraps the current context as a wgpu adapter (`None`: wgpu refused it, e.g. below GLES 3.0).
fn expose(instance: &wgpu::Instance, egl: &Egl, ctx: &GlesContext) -> Option<wgpu::Adapter> {
    ctx.make_current().ok()?;
    let exposed = unsafe {
        wgpu::hal::gles::Adapter::new_external(
            |name| {
                egl.get_proc_address(name)
                    .map_or(std::ptr::null(), |p| p as *const c_void)
            },
            wgpu::GlBackendOptions::default(),
        )
    }?;
    // Safety: the adapter's context stays alive with `ctx`, which the caller keeps with it.
    Some(unsafe { instance.create_adapter_from_hal(exposed) })
}
