//! Shared test fixtures: the ICT heads from `../shared`, a small synthetic face, and a minimal
//! glTF writer for building the file layouts other tools produce.
#![allow(
    dead_code,
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::float_cmp,
    reason = "tests panic to fail, and compare exact zeros (a zero delta means: does not move)"
)]

use serde_json::{Value, json};

/// A 9×9 bumpy grid, symmetric about x = 0, with `blink_L`, `blink_R` (mirror images) and `open`.
pub struct TinyFace {
    pub positions: Vec<[f32; 3]>,
    pub indices: Vec<u16>,
    pub shapes: Vec<(&'static str, Vec<[f32; 3]>)>,
}

pub fn tiny_face() -> TinyFace {
    let n = 9;
    let mut positions = Vec::new();
    for j in 0..n {
        for i in 0..n {
            let x = -1.0 + 2.0 * i as f32 / (n - 1) as f32;
            let y = -1.0 + 2.0 * j as f32 / (n - 1) as f32;
            positions.push([x, y, 0.3 * (1.0 - x * x) * (1.0 - y * y)]);
        }
    }
    let mut indices = Vec::new();
    for j in 0..n - 1 {
        for i in 0..n - 1 {
            let a = (j * n + i) as u16;
            let (b, c, d) = (a + 1, a + n as u16, a + n as u16 + 1);
            indices.extend_from_slice(&[a, b, d, a, d, c]);
        }
    }
    let blink = |side: f32| -> Vec<[f32; 3]> {
        positions
            .iter()
            .map(|p| {
                if p[0] * side > 0.2 && p[1] > 0.3 {
                    [0.02 * side, -0.1 * p[0].abs(), 0.01]
                } else {
                    [0.0; 3]
                }
            })
            .collect()
    };
    let open: Vec<[f32; 3]> = positions
        .iter()
        .map(|p| {
            if p[1] < -0.3 {
                [0.0, -0.2 * (-p[1]), -0.05]
            } else {
                [0.0; 3]
            }
        })
        .collect();
    let shapes = vec![
        ("blink_L", blink(1.0)),
        ("blink_R", blink(-1.0)),
        ("open", open),
    ];
    TinyFace {
        positions,
        indices,
        shapes,
    }
}

/// Buffer views and accessors over one binary buffer.
#[derive(Default)]
pub struct GltfBuilder {
    pub bin: Vec<u8>,
    pub views: Vec<Value>,
    pub accessors: Vec<Value>,
}

impl GltfBuilder {
    pub fn view(&mut self, bytes: &[u8]) -> usize {
        while !self.bin.len().is_multiple_of(4) {
            self.bin.push(0);
        }
        self.views
            .push(json!({"buffer": 0, "byteOffset": self.bin.len(), "byteLength": bytes.len()}));
        self.bin.extend_from_slice(bytes);
        self.views.len() - 1
    }

    pub fn vec3(&mut self, data: &[[f32; 3]]) -> usize {
        let bytes: Vec<u8> = data
            .iter()
            .flatten()
            .flat_map(|f| f.to_le_bytes())
            .collect();
        let view = self.view(&bytes);
        let mut min = [f32::INFINITY; 3];
        let mut max = [f32::NEG_INFINITY; 3];
        for p in data {
            for k in 0..3 {
                min[k] = min[k].min(p[k]);
                max[k] = max[k].max(p[k]);
            }
        }
        let to64 = |a: [f32; 3]| a.map(f64::from);
        self.accessors.push(json!({"bufferView": view, "componentType": 5126, "count": data.len(), "type": "VEC3", "min": to64(min), "max": to64(max)}));
        self.accessors.len() - 1
    }

    pub fn raw(&mut self, bytes: &[u8], component: u32, count: usize, kind: &str) -> usize {
        let view = self.view(bytes);
        self.accessors.push(
            json!({"bufferView": view, "componentType": component, "count": count, "type": kind}),
        );
        self.accessors.len() - 1
    }

    pub fn indices(&mut self, data: &[u16]) -> usize {
        let bytes: Vec<u8> = data.iter().flat_map(|i| i.to_le_bytes()).collect();
        self.raw(&bytes, 5123, data.len(), "SCALAR")
    }

    /// A sparse VEC3 accessor with no base view: zero except at the non-zero entries of `dense`.
    pub fn sparse_vec3(&mut self, dense: &[[f32; 3]]) -> usize {
        let idx: Vec<u32> = (0..dense.len() as u32)
            .filter(|&i| dense[i as usize] != [0.0; 3])
            .collect();
        let ib: Vec<u8> = idx.iter().flat_map(|i| i.to_le_bytes()).collect();
        let vb: Vec<u8> = idx
            .iter()
            .flat_map(|&i| dense[i as usize])
            .flat_map(|f| f.to_le_bytes())
            .collect();
        let iv = self.view(&ib);
        let vv = self.view(&vb);
        self.accessors.push(json!({
            "componentType": 5126, "count": dense.len(), "type": "VEC3",
            "sparse": {"count": idx.len(), "indices": {"bufferView": iv, "componentType": 5125}, "values": {"bufferView": vv}}
        }));
        self.accessors.len() - 1
    }

    fn attach(&self, root: &mut Value, buffer: Value) {
        root["asset"] = json!({"version": "2.0"});
        root["accessors"] = json!(self.accessors);
        root["bufferViews"] = json!(self.views);
        root["buffers"] = json!([buffer]);
    }

    pub fn glb(self, mut root: Value) -> Vec<u8> {
        self.attach(&mut root, json!({"byteLength": self.bin.len()}));
        faceanim_testdata::glb::assemble(&root, &self.bin)
    }

    /// JSON with the buffer at `uri` (the caller serves `self.bin` under that name).
    pub fn gltf_external(self, mut root: Value, uri: &str) -> (Vec<u8>, Vec<u8>) {
        self.attach(&mut root, json!({"byteLength": self.bin.len(), "uri": uri}));
        (serde_json::to_vec(&root).unwrap(), self.bin)
    }

    /// JSON with the buffer embedded as a base64 data URI.
    pub fn gltf_data_uri(self, mut root: Value) -> Vec<u8> {
        use base64::Engine as _;
        let uri = format!(
            "data:application/octet-stream;base64,{}",
            base64::engine::general_purpose::STANDARD.encode(&self.bin)
        );
        self.attach(&mut root, json!({"byteLength": self.bin.len(), "uri": uri}));
        serde_json::to_vec(&root).unwrap()
    }
}

/// The tiny face as one mesh with one primitive, in `builder`; returns the root JSON.
pub fn tiny_face_gltf(builder: &mut GltfBuilder, face: &TinyFace, sparse_targets: bool) -> Value {
    let position = builder.vec3(&face.positions);
    let indices = builder.indices(&face.indices);
    let targets: Vec<Value> = face
        .shapes
        .iter()
        .map(|(_, d)| json!({"POSITION": if sparse_targets { builder.sparse_vec3(d) } else { builder.vec3(d) }}))
        .collect();
    let names: Vec<&str> = face.shapes.iter().map(|(n, _)| *n).collect();
    json!({
        "scene": 0, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0, "name": "face"}],
        "meshes": [{"name": "face", "primitives": [{"attributes": {"POSITION": position}, "indices": indices, "targets": targets}],
                    "extras": {"targetNames": names}}]
    })
}
