//! ABI checks against the linked Embree library: struct layouts, and an instanced hit written
//! by the library into a ray-hit guarded by canaries. A header/library mismatch (the crates.io
//! `embree4-sys` 4.2 headers against a 4.3+ library) makes the library write past
//! `RTCRayHit`, which the canaries catch.

use std::mem::{offset_of, size_of};
use std::ptr;

use embree4_sys::*;

#[test]
fn ray_layout_matches_embree_abi() {
    assert_eq!(size_of::<RTCRay>(), 48);
    assert_eq!(offset_of!(RTCRay, tfar), 32);
    assert_eq!(offset_of!(RTCRayHit, hit), 48);
    let levels = RTC_MAX_INSTANCE_LEVEL_COUNT as usize;
    // Ng, u, v, primID, geomID, then instID[levels] (and instPrimID[levels] with instance
    // arrays), padded to 16 bytes.
    #[cfg(embree_instance_array)]
    let hit_fields = 7 * 4 + 2 * 4 * levels;
    #[cfg(not(embree_instance_array))]
    let hit_fields = 7 * 4 + 4 * levels;
    assert_eq!(size_of::<RTCHit>(), hit_fields.next_multiple_of(16));
    assert_eq!(RAY_HIT_SIZE, 48 + size_of::<RTCHit>());
}

#[cfg(embree_instance_array)]
#[test]
fn hit_has_instance_primitive_ids_when_configured() {
    assert_eq!(
        offset_of!(RTCHit, instPrimID),
        offset_of!(RTCHit, instID) + 4 * RTC_MAX_INSTANCE_LEVEL_COUNT as usize
    );
}

const CANARY: u32 = 0xDEAD_BEEF;

#[repr(C, align(16))]
struct Guarded {
    before: [u32; 16],
    rayhit: RTCRayHit,
    after: [u32; 32],
}

/// A single triangle in the z = 0 plane: (0,0,0), (1,0,0), (0,1,0).
unsafe fn triangle_scene(device: RTCDevice) -> RTCScene {
    // SAFETY (whole fn): valid device; buffers returned by Embree have the requested sizes.
    unsafe {
        let geom = rtcNewGeometry(device, RTCGeometryType::RTC_GEOMETRY_TYPE_TRIANGLE);
        let vb = rtcSetNewGeometryBuffer(
            geom,
            RTCBufferType::RTC_BUFFER_TYPE_VERTEX,
            0,
            RTCFormat::RTC_FORMAT_FLOAT3,
            12,
            3,
        ) as *mut [f32; 3];
        vb.write([0.0, 0.0, 0.0]);
        vb.add(1).write([1.0, 0.0, 0.0]);
        vb.add(2).write([0.0, 1.0, 0.0]);
        let ib = rtcSetNewGeometryBuffer(
            geom,
            RTCBufferType::RTC_BUFFER_TYPE_INDEX,
            0,
            RTCFormat::RTC_FORMAT_UINT3,
            12,
            1,
        ) as *mut [u32; 3];
        ib.write([0, 1, 2]);
        rtcCommitGeometry(geom);
        let scene = rtcNewScene(device);
        rtcAttachGeometry(scene, geom);
        rtcReleaseGeometry(geom);
        rtcCommitScene(scene);
        scene
    }
}

#[test]
fn instanced_hit_reports_inst_id_and_leaves_neighbours_intact() {
    // SAFETY: straight-line use of the C API with valid handles, released at the end; the
    // ray-hit lives in a repr(C) struct whose canaries detect any out-of-bounds write.
    unsafe {
        let device = rtcNewDevice(ptr::null());
        assert!(!device.is_null());
        let prototype = triangle_scene(device);
        let top = rtcNewScene(device);
        // Occupy id 0 with another instance, so the hit must report instID 1.
        for translate_x in [100.0f32, 0.0] {
            let inst = rtcNewGeometry(device, RTCGeometryType::RTC_GEOMETRY_TYPE_INSTANCE);
            rtcSetGeometryInstancedScene(inst, prototype);
            let xf: [f32; 12] = [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, translate_x, 0.0, 2.0];
            rtcSetGeometryTransform(inst, 0, RTCFormat::RTC_FORMAT_FLOAT3X4_COLUMN_MAJOR, xf.as_ptr().cast());
            rtcCommitGeometry(inst);
            rtcAttachGeometry(top, inst);
            rtcReleaseGeometry(inst);
        }
        rtcCommitScene(top);
        assert_eq!(rtcGetDeviceError(device), RTCError::RTC_ERROR_NONE);

        let mut g = Guarded { before: [CANARY; 16], rayhit: RTCRayHit::default(), after: [CANARY; 32] };
        g.rayhit.ray = RTCRay {
            org_x: 0.25,
            org_y: 0.25,
            org_z: 0.0,
            dir_z: 1.0,
            tfar: f32::INFINITY,
            mask: u32::MAX,
            ..Default::default()
        };
        g.rayhit.hit.geomID = RTC_INVALID_GEOMETRY_ID;
        g.rayhit.hit.instID = [RTC_INVALID_GEOMETRY_ID; RTC_MAX_INSTANCE_LEVEL_COUNT as usize];
        rtcIntersect1(top, &mut g.rayhit, ptr::null_mut());

        assert!(g.before.iter().all(|&c| c == CANARY), "Embree wrote before RTCRayHit");
        assert!(
            g.after.iter().all(|&c| c == CANARY),
            "Embree wrote past RTCRayHit: headers do not match the library"
        );
        let hit = &g.rayhit.hit;
        assert_eq!(hit.instID[0], 1);
        assert_eq!(hit.geomID, 0);
        assert_eq!(hit.primID, 0);
        assert!((g.rayhit.ray.tfar - 2.0).abs() < 1e-6, "t = {}", g.rayhit.ray.tfar);
        assert!((hit.u - 0.25).abs() < 1e-6 && (hit.v - 0.25).abs() < 1e-6);

        rtcReleaseScene(top);
        rtcReleaseScene(prototype);
        rtcReleaseDevice(device);
    }
}
