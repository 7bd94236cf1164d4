//! What the engines render of each Mitsuba BSDF plugin a material is made of: the one record
//! behind the warnings about the chosen engine's approximations and `--plan`'s lines on
//! materials (docs/scene-format.md's table says the same for every plugin).

/// A BSDF plugin as the engines render it.
#[derive(Clone, Debug, PartialEq)]
pub struct PluginSupport {
    /// The plugin's type as the file gives it (`roughplastic`, `mask`).
    pub kind: String,
    /// Where the file gives it (`file:line:column`), for the warnings.
    pub at: String,
    /// What the path tracer renders in its place; None: the plugin, exactly.
    pub path: Option<&'static str>,
    /// What the other engines render in its place; None: the plugin, exactly.
    pub others: Option<&'static str>,
}

impl PluginSupport {
    /// What the path tracer (`path_tracer`) or the other engines render in the plugin's
    /// place; None: the plugin, exactly.
    pub fn approximation(&self, path_tracer: bool) -> Option<&'static str> {
        if path_tracer {
            self.path
        } else {
            self.others
        }
    }

    /// The warning for a render by `engine` (the path tracer when `path_tracer`); None when
    /// that engine renders the plugin exactly. It says where the path tracer is exact, which
    /// is what a user of another engine can switch to.
    pub fn warning(&self, engine: &str, path_tracer: bool) -> Option<String> {
        let how = self.approximation(path_tracer)?;
        let exact_elsewhere = if !path_tracer && self.path.is_none() {
            " (the path tracer renders it exactly)"
        } else {
            ""
        };
        Some(format!(
            "{}: {}: the {engine} engine approximates it as {how}{exact_elsewhere}",
            self.at, self.kind
        ))
    }
}

/// A material made of Mitsuba BSDF plugins, as the engines render it.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MitsubaBsdf {
    /// The outermost plugin's `id`, if the file gives one.
    pub id: Option<String>,
    /// Its plugins, outermost first (`twosided`, then the `roughplastic` inside it).
    pub plugins: Vec<PluginSupport>,
}

impl MitsubaBsdf {
    /// The plugins' types nested as in the file: `mask(twosided(roughplastic))`.
    pub fn kinds(&self) -> String {
        let names: Vec<&str> = self.plugins.iter().map(|p| p.kind.as_str()).collect();
        format!(
            "{}{}",
            names.join("("),
            ")".repeat(names.len().saturating_sub(1))
        )
    }

    /// What the path tracer (`path_tracer`) or the other engines render: "exact", or each
    /// plugin they approximate and how.
    pub fn rendering(&self, path_tracer: bool) -> String {
        let approximated: Vec<String> = self
            .plugins
            .iter()
            .filter_map(|p| {
                p.approximation(path_tracer)
                    .map(|how| format!("{} approximated as {how}", p.kind))
            })
            .collect();
        if approximated.is_empty() {
            "exact".into()
        } else {
            approximated.join("; ")
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn plugin(
        kind: &str,
        path: Option<&'static str>,
        others: Option<&'static str>,
    ) -> PluginSupport {
        PluginSupport {
            kind: kind.into(),
            at: "s.xml:3:5".into(),
            path,
            others,
        }
    }

    #[test]
    fn nested_plugins_name_each_approximation_for_each_engine() {
        let m = MitsubaBsdf {
            id: Some("coat".into()),
            plugins: vec![
                plugin("mask", None, Some("its nested BSDF, opaque")),
                plugin("twosided", None, None),
                plugin("roughplastic", None, Some("a Lambertian base")),
            ],
        };
        assert_eq!(m.kinds(), "mask(twosided(roughplastic))");
        assert_eq!(m.rendering(true), "exact");
        assert_eq!(
            m.rendering(false),
            "mask approximated as its nested BSDF, opaque; roughplastic approximated as a Lambertian base"
        );
        assert_eq!(m.plugins[1].warning("raytrace", false), None);
        assert_eq!(m.plugins[2].warning("path", true), None);
        assert_eq!(
            m.plugins[2].warning("photon", false).as_deref(),
            Some("s.xml:3:5: roughplastic: the photon engine approximates it as a Lambertian base (the path tracer renders it exactly)")
        );
        assert_eq!(
            plugin("someplugin", Some("a Lambertian base"), None)
                .warning("path", true)
                .as_deref(),
            Some("s.xml:3:5: someplugin: the path engine approximates it as a Lambertian base")
        );
    }
}
