//! The ROS 2 messages a bag holds, each with its `ros2msg` schema (the message's definition,
//! then every type it uses after a line of 80 `=` and `MSG: package/Type`, as rosbag2 stores
//! them in MCAP) and its CDR encoding, field by field in the definition's order.

use glam::{DQuat, DVec3};

use super::cdr::Cdr;

/// A message type: its ROS 2 name and its `ros2msg` schema.
pub struct MsgType {
    pub name: &'static str,
    pub schema: String,
}

const TIME: &str = "int32 sec\nuint32 nanosec\n";
const HEADER: &str = "builtin_interfaces/Time stamp\nstring frame_id\n";
const VECTOR3: &str = "float64 x\nfloat64 y\nfloat64 z\n";
const QUATERNION: &str = "float64 x 0\nfloat64 y 0\nfloat64 z 0\nfloat64 w 1\n";
const TRANSFORM: &str = "Vector3 translation\nQuaternion rotation\n";

/// A definition and its dependencies, in the order given.
fn schema(top: &str, deps: &[(&str, &str)]) -> String {
    let mut s = top.to_owned();
    for (name, def) in deps {
        s.push_str(&"=".repeat(80));
        s.push_str(&format!("\nMSG: {name}\n{def}"));
    }
    s
}

fn header_deps() -> [(&'static str, &'static str); 2] {
    [
        ("std_msgs/Header", HEADER),
        ("builtin_interfaces/Time", TIME),
    ]
}

pub fn image_type() -> MsgType {
    let def = "std_msgs/Header header\nuint32 height\nuint32 width\nstring encoding\n\
               uint8 is_bigendian\nuint32 step\nuint8[] data\n";
    MsgType {
        name: "sensor_msgs/msg/Image",
        schema: schema(def, &header_deps()),
    }
}

pub fn camera_info_type() -> MsgType {
    let def = "std_msgs/Header header\nuint32 height\nuint32 width\nstring distortion_model\n\
               float64[] d\nfloat64[9] k\nfloat64[9] r\nfloat64[12] p\nuint32 binning_x\n\
               uint32 binning_y\nRegionOfInterest roi\n";
    let roi = "uint32 x_offset\nuint32 y_offset\nuint32 height\nuint32 width\nbool do_rectify\n";
    let [h, t] = header_deps();
    MsgType {
        name: "sensor_msgs/msg/CameraInfo",
        schema: schema(def, &[h, t, ("sensor_msgs/RegionOfInterest", roi)]),
    }
}

pub fn tf_type() -> MsgType {
    let stamped = "std_msgs/Header header\nstring child_frame_id\nTransform transform\n";
    let [h, t] = header_deps();
    MsgType {
        name: "tf2_msgs/msg/TFMessage",
        schema: schema(
            "geometry_msgs/TransformStamped[] transforms\n",
            &[
                ("geometry_msgs/TransformStamped", stamped),
                h,
                t,
                ("geometry_msgs/Transform", TRANSFORM),
                ("geometry_msgs/Vector3", VECTOR3),
                ("geometry_msgs/Quaternion", QUATERNION),
            ],
        ),
    }
}

pub fn odometry_type() -> MsgType {
    let def = "std_msgs/Header header\nstring child_frame_id\n\
               geometry_msgs/PoseWithCovariance pose\ngeometry_msgs/TwistWithCovariance twist\n";
    let [h, t] = header_deps();
    MsgType {
        name: "nav_msgs/msg/Odometry",
        schema: schema(
            def,
            &[
                h,
                t,
                (
                    "geometry_msgs/PoseWithCovariance",
                    "Pose pose\nfloat64[36] covariance\n",
                ),
                (
                    "geometry_msgs/Pose",
                    "Point position\nQuaternion orientation\n",
                ),
                ("geometry_msgs/Point", VECTOR3),
                ("geometry_msgs/Quaternion", QUATERNION),
                (
                    "geometry_msgs/TwistWithCovariance",
                    "Twist twist\nfloat64[36] covariance\n",
                ),
                ("geometry_msgs/Twist", "Vector3 linear\nVector3 angular\n"),
                ("geometry_msgs/Vector3", VECTOR3),
            ],
        ),
    }
}

pub fn point_cloud_type() -> MsgType {
    let def = "std_msgs/Header header\nuint32 height\nuint32 width\nPointField[] fields\n\
               bool is_bigendian\nuint32 point_step\nuint32 row_step\nuint8[] data\n\
               bool is_dense\n";
    let field = "uint8 INT8 = 1\nuint8 UINT8 = 2\nuint8 INT16 = 3\nuint8 UINT16 = 4\n\
                 uint8 INT32 = 5\nuint8 UINT32 = 6\nuint8 FLOAT32 = 7\nuint8 FLOAT64 = 8\n\
                 string name\nuint32 offset\nuint8 datatype\nuint32 count\n";
    let [h, t] = header_deps();
    MsgType {
        name: "sensor_msgs/msg/PointCloud2",
        schema: schema(def, &[h, t, ("sensor_msgs/PointField", field)]),
    }
}

/// A time in nanoseconds since the bag's epoch, as `builtin_interfaces/Time`.
fn header(c: &mut Cdr, stamp_ns: u64, frame_id: &str) {
    let sec = i32::try_from(stamp_ns / 1_000_000_000).unwrap_or(i32::MAX);
    c.i32(sec).u32((stamp_ns % 1_000_000_000) as u32);
    c.string(frame_id);
}

/// An image's rows, `step` bytes each, in the named `sensor_msgs` encoding.
pub struct Image<'a> {
    pub width: u32,
    pub height: u32,
    pub encoding: &'static str,
    pub step: u32,
    pub data: &'a [u8],
}

pub fn image(stamp_ns: u64, frame_id: &str, im: &Image) -> Vec<u8> {
    let mut c = Cdr::with_capacity(im.data.len());
    header(&mut c, stamp_ns, frame_id);
    c.u32(im.height).u32(im.width).string(im.encoding);
    c.u8(0).u32(im.step).byte_seq(im.data);
    c.into_bytes()
}

/// A camera's intrinsics as `CameraInfo` holds them.
pub struct Intrinsics {
    pub width: u32,
    pub height: u32,
    pub distortion_model: String,
    pub d: Vec<f64>,
    /// Row-major 3x3.
    pub k: [f64; 9],
}

pub fn camera_info(stamp_ns: u64, frame_id: &str, i: &Intrinsics) -> Vec<u8> {
    let mut c = Cdr::new();
    header(&mut c, stamp_ns, frame_id);
    c.u32(i.height).u32(i.width).string(&i.distortion_model);
    c.f64_seq(&i.d).f64s(&i.k);
    c.f64s(&[1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0]);
    let k = &i.k;
    c.f64s(&[
        k[0], k[1], k[2], 0.0, k[3], k[4], k[5], 0.0, 0.0, 0.0, 1.0, 0.0,
    ]);
    c.u32(0).u32(0);
    c.u32(0).u32(0).u32(0).u32(0).bool(false);
    c.into_bytes()
}

/// One transform: `child` in `parent`'s frame (the child's origin and the rotation taking its
/// axes to the parent's).
#[derive(Clone, Copy)]
pub struct Transform<'a> {
    pub stamp_ns: u64,
    pub parent: &'a str,
    pub child: &'a str,
    pub translation: DVec3,
    pub rotation: DQuat,
}

pub fn tf(transforms: &[Transform]) -> Vec<u8> {
    let mut c = Cdr::new();
    c.len(transforms.len());
    for t in transforms {
        header(&mut c, t.stamp_ns, t.parent);
        c.string(t.child);
        vec3(&mut c, t.translation);
        quat(&mut c, t.rotation);
    }
    c.into_bytes()
}

fn vec3(c: &mut Cdr, v: DVec3) {
    c.f64(v.x).f64(v.y).f64(v.z);
}

fn quat(c: &mut Cdr, q: DQuat) {
    c.f64(q.x).f64(q.y).f64(q.z).f64(q.w);
}

/// Ground-truth odometry: the pose of `child` in `parent`, and its velocity in `child`'s
/// axes. The covariances are zero: the values are exact.
pub struct Odometry<'a> {
    pub pose: Transform<'a>,
    pub linear: DVec3,
    pub angular: DVec3,
}

pub fn odometry(o: &Odometry) -> Vec<u8> {
    let mut c = Cdr::new();
    header(&mut c, o.pose.stamp_ns, o.pose.parent);
    c.string(o.pose.child);
    vec3(&mut c, o.pose.translation);
    quat(&mut c, o.pose.rotation);
    c.f64s(&[0.0; 36]);
    vec3(&mut c, o.linear);
    vec3(&mut c, o.angular);
    c.f64s(&[0.0; 36]);
    c.into_bytes()
}

/// `PointField`'s datatypes used here.
pub const FLOAT32: u8 = 7;
pub const UINT32: u8 = 6;

/// An unordered cloud (height 1) of `points` points, each `fields` (name, offset, datatype),
/// little-endian, `step` bytes a point.
pub struct Cloud<'a> {
    pub fields: &'a [(&'a str, u32, u8)],
    pub step: u32,
    pub points: u32,
    pub data: &'a [u8],
}

pub fn point_cloud(stamp_ns: u64, frame_id: &str, cloud: &Cloud) -> Vec<u8> {
    let mut c = Cdr::with_capacity(cloud.data.len());
    header(&mut c, stamp_ns, frame_id);
    c.u32(1).u32(cloud.points);
    c.len(cloud.fields.len());
    for &(name, offset, datatype) in cloud.fields {
        c.string(name).u32(offset).u8(datatype).u32(1);
    }
    c.bool(false).u32(cloud.step).u32(cloud.step * cloud.points);
    c.byte_seq(cloud.data).bool(true);
    c.into_bytes()
}
