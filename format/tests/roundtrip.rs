//! Property tests: any container whose arrays have consistent shapes survives write -> read
//! unchanged, and writing is deterministic.

use hce_format::*;
use proptest::prelude::*;

fn object() -> impl Strategy<Value = Object> {
    (
        0usize..12,
        0usize..12,
        0usize..30,
        0usize..10,
        0u64..200,
        0usize..40,
    )
        .prop_flat_map(|(v, f, r, nn, bit_len, nc)| {
            let words = bit_len.div_ceil(32) as usize;
            (
                "[a-z ]{0,12}",
                prop::bool::ANY,
                any::<u64>(),
                prop::collection::vec(-1e6f32..1e6, 3 * v),
                prop::collection::vec(any::<u32>(), 3 * f * 4),
                prop::collection::vec(any::<u32>(), v + 1 + v),
                prop::collection::vec(any::<u32>(), 2 * r),
                prop::collection::vec(0u32..1000, 3 * f),
                prop::collection::vec(any::<u32>(), 4 * f),
                prop::collection::vec(prop::array::uniform3(-1f32..1.0), nn),
                prop::collection::vec(any::<u32>(), words),
                prop::collection::vec(any::<u32>(), nc),
            )
                .prop_map(
                    move |(
                        name,
                        flat,
                        hash,
                        positions,
                        tri,
                        vert,
                        ring,
                        edges,
                        rec,
                        normals,
                        bits,
                        colours,
                    )| {
                        Object {
                            name,
                            kind: if flat {
                                ObjectKind::Flat
                            } else {
                                ObjectKind::Multiresolution
                            },
                            geometry_hash: hash,
                            mesh: ControlMesh {
                                positions,
                                triangles: tri[..3 * f].to_vec(),
                                corner_spokes: tri[3 * f..6 * f].to_vec(),
                                neighbours: tri[6 * f..9 * f].to_vec(),
                                ring_offsets: vert[..v + 1].to_vec(),
                                vertex_flags: vert[v + 1..].to_vec(),
                                ring: ring[..r].to_vec(),
                                spoke_flags: ring[r..].to_vec(),
                                edges,
                            },
                            triangles: rec
                                .chunks(4)
                                .map(|t| TriangleRecord {
                                    bits_start: t[0],
                                    colour_start: t[1],
                                    normal_start: t[2],
                                    normal_count: t[3],
                                })
                                .collect(),
                            normals,
                            bits,
                            bit_len,
                            // Half the objects carry corner colours (SPEC.md A.10, optional).
                            corner_colours: if hash % 2 == 1 {
                                colours
                                    .iter()
                                    .flat_map(|&c| [c, c ^ 1, c.rotate_left(7)])
                                    .collect()
                            } else {
                                Vec::new()
                            },
                            colours,
                        }
                    },
                )
        })
}

fn container() -> impl Strategy<Value = Container> {
    (
        ".{0,20}",
        ".{0,40}",
        any::<u64>(),
        prop::collection::vec(object(), 0..4),
    )
        .prop_map(
            |(generator, bake_parameters, source_hash, objects)| Container {
                metadata: Metadata {
                    generator,
                    bake_parameters,
                    source_hash,
                },
                objects,
            },
        )
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]

    #[test]
    fn write_read_round_trips(c in container()) {
        let bytes = write(&c).unwrap();
        let back = read(&bytes).unwrap();
        prop_assert_eq!(&back, &c);
        prop_assert_eq!(write(&back).unwrap(), bytes.clone());
        // Every section is 256-aligned and the structure alone is valid: any problem the
        // validator finds is about content, never about the file layout.
        for p in validate_bytes(&bytes) {
            prop_assert!(
                p.location.starts_with("objects[") || p.location == "metadata.bake_parameters",
                "{}",
                p
            );
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(40))]

    /// What a correct builder produces, the validator accepts, and it survives the file.
    #[test]
    fn valid_grids_validate_and_round_trip(n in 1u32..7, depth in 0u32..5) {
        let c = example::grid(n, depth);
        let bytes = write(&c).unwrap();
        prop_assert_eq!(validate_bytes(&bytes), vec![]);
        prop_assert_eq!(read(&bytes).unwrap(), c);
    }
}
