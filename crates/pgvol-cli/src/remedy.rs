//! The command line's flags for what the library says would make a refused call work.

use pgvol::Remedy;

/// The flag that applies `remedy`, as a short phrase for the end of an error message.
pub fn flag_hint(remedy: Remedy) -> Option<String> {
    Some(match remedy {
        Remedy::Replace => "--force replaces it".to_string(),
        Remedy::MemoryLimit => "--max-memory sets the limit".to_string(),
        Remedy::Band(spacings) => format!("pgvol encode MESH --band {spacings} writes such a file"),
        Remedy::FinerGrid => "--res sets the grid".to_string(),
        Remedy::CoveringBox => "--box x0,y0,z0,x1,y1,z1".to_string(),
        _ => return None,
    })
}

/// The hint for the first library error in `e`'s chain that carries a remedy.
pub fn hint_for(e: &anyhow::Error) -> Option<String> {
    e.chain()
        .filter_map(|cause| cause.downcast_ref::<pgvol::Error>())
        .find_map(|error| error.remedy())
        .and_then(flag_hint)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn library_remedies_are_named_by_their_flags() {
        let e = anyhow::Error::new(
            pgvol::Error::parameter("too narrow").with_remedy(Remedy::Band(12.0)),
        )
        .context("decoding x.pgv");
        assert_eq!(
            hint_for(&e).as_deref(),
            Some("pgvol encode MESH --band 12 writes such a file")
        );
        let plain = anyhow::Error::new(pgvol::Error::parameter("bad"));
        assert_eq!(hint_for(&plain), None);
        for remedy in [
            Remedy::Replace,
            Remedy::MemoryLimit,
            Remedy::FinerGrid,
            Remedy::CoveringBox,
        ] {
            assert!(
                flag_hint(remedy).is_some_and(|h| h.starts_with("--")),
                "{remedy:?}"
            );
        }
    }
}
