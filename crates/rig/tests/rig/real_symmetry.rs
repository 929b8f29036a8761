//! Symmetry on real faces: the four ICT identities in `../shared` (the generic face and three
//! real people, none exactly symmetric) with every blendshape renamed `shape_N` and shuffled, so
//! that only geometry can pair them. Each must find at least 20 of the 22 left/right pairs the
//! names give, with none wrong and no side swapped.

use faceanim_testdata::{ICT_IDENTITIES, ict, ict_identity, renamed_and_shuffled};

#[test]
fn geometry_pairs_at_least_20_of_22_on_every_identity_and_none_wrong() {
    let truth: Vec<(String, String)> = ict()
        .symmetry()
        .pairs()
        .iter()
        .map(|p| {
            (
                ict().blendshapes()[p.left.index()].name().to_owned(),
                ict().blendshapes()[p.right.index()].name().to_owned(),
            )
        })
        .collect();
    assert_eq!(truth.len(), 22);
    let mut report = Vec::new();
    for file in ICT_IDENTITIES {
        let named = ict_identity(file);
        let plane = named.symmetry().plane().expect("a face has a mirror plane");
        assert!(plane.tilt_degrees() < 3.0, "{file}: {plane:?}");
        assert!(
            named.symmetry().mirrored_fraction() > 0.8,
            "{file}: {} of the vertices have a mirror",
            named.symmetry().mirrored_fraction()
        );
        for seed in [3, 19] {
            let (c, order) = renamed_and_shuffled(named, seed);
            let name = |i: usize| named.blendshapes()[order[i]].name().to_owned();
            let found: Vec<(String, String)> = c
                .symmetry()
                .pairs()
                .iter()
                .map(|p| (name(p.left.index()), name(p.right.index())))
                .collect();
            let wrong: Vec<_> = found.iter().filter(|f| !truth.contains(f)).collect();
            assert!(wrong.is_empty(), "{file}: wrong pairs {wrong:?}");
            assert!(
                found.len() >= 20,
                "{file}: only {} of 22: {found:?}",
                found.len()
            );
            let missing: Vec<_> = truth.iter().filter(|t| !found.contains(t)).collect();
            report.push(format!(
                "{file}: {} of 22, missing {missing:?}",
                found.len()
            ));
        }
    }
    eprintln!("{}", report.join("\n"));
}
