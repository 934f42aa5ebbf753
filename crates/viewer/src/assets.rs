//! The page's files, embedded in the binary so that `echothigh view` works on
//! a fresh machine after `cargo build` alone. three.js is vendored (built ES
//! modules plus its MIT licence) by `web/update-vendor.sh` from the version
//! pinned in `web/package-lock.json`.

/// One embedded file.
#[derive(Debug, Clone, Copy)]
pub struct Asset {
    /// URL path, starting with `/`.
    pub path: &'static str,
    /// `Content-Type` header value.
    pub content_type: &'static str,
    /// File contents.
    pub body: &'static [u8],
}

const JS: &str = "text/javascript; charset=utf-8";

/// Every file the page needs.
pub const ASSETS: &[Asset] = &[
    Asset {
        path: "/index.html",
        content_type: "text/html; charset=utf-8",
        body: include_bytes!("../assets/web/index.html"),
    },
    Asset {
        path: "/style.css",
        content_type: "text/css; charset=utf-8",
        body: include_bytes!("../assets/web/style.css"),
    },
    Asset {
        path: "/app.js",
        content_type: JS,
        body: include_bytes!("../assets/web/app.js"),
    },
    Asset {
        path: "/scene.js",
        content_type: JS,
        body: include_bytes!("../assets/web/scene.js"),
    },
    Asset {
        path: "/scene_proxy.js",
        content_type: JS,
        body: include_bytes!("../assets/web/scene_proxy.js"),
    },
    Asset {
        path: "/scene_worker.js",
        content_type: JS,
        body: include_bytes!("../assets/web/scene_worker.js"),
    },
    Asset {
        path: "/echo_worker.js",
        content_type: JS,
        body: include_bytes!("../assets/web/echo_worker.js"),
    },
    Asset {
        path: "/image_stream.js",
        content_type: JS,
        body: include_bytes!("../assets/web/image_stream.js"),
    },
    Asset {
        path: "/panels.js",
        content_type: JS,
        body: include_bytes!("../assets/web/panels.js"),
    },
    Asset {
        path: "/device.js",
        content_type: JS,
        body: include_bytes!("../assets/web/device.js"),
    },
    Asset {
        path: "/exam.js",
        content_type: JS,
        body: include_bytes!("../assets/web/exam.js"),
    },
    Asset {
        path: "/guide.js",
        content_type: JS,
        body: include_bytes!("../assets/web/guide.js"),
    },
    Asset {
        path: "/doppler.js",
        content_type: JS,
        body: include_bytes!("../assets/web/doppler.js"),
    },
    Asset {
        path: "/vendor/three.module.min.js",
        content_type: JS,
        body: include_bytes!("../assets/web/vendor/three.module.min.js"),
    },
    Asset {
        path: "/vendor/three.core.min.js",
        content_type: JS,
        body: include_bytes!("../assets/web/vendor/three.core.min.js"),
    },
    Asset {
        path: "/vendor/LICENSE-three.txt",
        content_type: "text/plain; charset=utf-8",
        body: include_bytes!("../assets/web/vendor/LICENSE-three.txt"),
    },
];

/// The asset served at URL `path` (`/` is `/index.html`).
pub fn lookup(path: &str) -> Option<&'static Asset> {
    let path = if path == "/" { "/index.html" } else { path };
    ASSETS.iter().find(|a| a.path == path)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn root_is_the_page_and_unknown_paths_are_absent() {
        let page = lookup("/").unwrap();
        assert!(page.content_type.starts_with("text/html"));
        assert!(std::str::from_utf8(page.body).unwrap().contains("app.js"));
        assert!(lookup("/../Cargo.toml").is_none());
        assert!(lookup("/nope.js").is_none());
    }

    #[test]
    fn vendored_three_is_complete_and_licensed() {
        let module =
            std::str::from_utf8(lookup("/vendor/three.module.min.js").unwrap().body).unwrap();
        // The module imports its core by relative path; it must be served too.
        assert!(module.contains("./three.core.min.js"));
        assert!(lookup("/vendor/three.core.min.js").unwrap().body.len() > 100_000);
        let licence =
            std::str::from_utf8(lookup("/vendor/LICENSE-three.txt").unwrap().body).unwrap();
        assert!(licence.contains("MIT License"));
    }

    #[test]
    fn every_script_the_page_imports_is_embedded() {
        for a in ASSETS
            .iter()
            .filter(|a| a.path.ends_with(".js") || a.path.ends_with(".html"))
        {
            let text = std::str::from_utf8(a.body).unwrap();
            for quote in ['"', '\''] {
                for part in text.split(quote) {
                    let local =
                        part.starts_with("./") && (part.ends_with(".js") || part.ends_with(".css"));
                    if local && !a.path.starts_with("/vendor/") {
                        assert!(
                            lookup(&part[1..]).is_some(),
                            "{} imports missing {part}",
                            a.path
                        );
                    }
                }
            }
        }
    }
}
