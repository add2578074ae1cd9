//! MiniUNet: the fully convolutional affordance network, one grasp-centre score per pixel.
//!
//! Parameter names follow the reference PyTorch module's state_dict (`inc.0.weight`,
//! `down1.1.weight`, ...), so weights move between the two tools. Initialisation matches
//! PyTorch's defaults (uniform ±1/√fan_in for weights and biases).

use tch::nn::{self, Module};
use tch::{Kind, Tensor};

use crate::data::input::InputKind;
use crate::named::named_enum;

named_enum! {
    /// Arithmetic the forward pass runs in.
    #[derive(serde::Deserialize)]
    pub enum Precision {
        /// Plain float32.
        Fp32 = "fp32", "plain float32",
        /// bfloat16 convolutions in channels_last layout over float32 master weights; the logits
        /// come back as float32 for the loss.
        Bf16 = "bf16", "bfloat16 convolutions over float32 master weights",
    }
}

/// The parameter names of the reference module, in its state_dict order.
#[cfg(test)]
pub(crate) const PARAMETER_NAMES: [&str; 16] = [
    "inc.0.weight",
    "inc.0.bias",
    "down1.1.weight",
    "down1.1.bias",
    "down2.1.weight",
    "down2.1.bias",
    "upconv1.weight",
    "upconv1.bias",
    "conv1.0.weight",
    "conv1.0.bias",
    "upconv2.weight",
    "upconv2.bias",
    "conv2.0.weight",
    "conv2.0.bias",
    "outc.weight",
    "outc.bias",
];

/// The network.
#[derive(Debug)]
pub struct MiniUNet {
    inc: nn::Conv2D,
    down1: nn::Conv2D,
    down2: nn::Conv2D,
    upconv1: nn::ConvTranspose2D,
    conv1: nn::Conv2D,
    upconv2: nn::ConvTranspose2D,
    conv2: nn::Conv2D,
    outc: nn::Conv2D,
}

/// PyTorch's default initialisation bound for a layer with this fan-in.
fn pytorch_uniform(fan_in: i64) -> nn::Init {
    let bound = 1.0 / (fan_in as f64).sqrt();
    nn::Init::Uniform {
        lo: -bound,
        up: bound,
    }
}

fn conv(path: nn::Path, input: i64, output: i64, kernel: i64) -> nn::Conv2D {
    let init = pytorch_uniform(input * kernel * kernel);
    nn::conv2d(
        path,
        input,
        output,
        kernel,
        nn::ConvConfig {
            padding: kernel / 2,
            ws_init: init,
            bs_init: init,
            ..Default::default()
        },
    )
}

fn up(path: nn::Path, input: i64, output: i64) -> nn::ConvTranspose2D {
    // PyTorch takes a transposed conv's fan-in from the weight's second dimension.
    let init = pytorch_uniform(output * 2 * 2);
    nn::conv_transpose2d(
        path,
        input,
        output,
        2,
        nn::ConvTransposeConfig {
            stride: 2,
            ws_init: init,
            bs_init: init,
            ..Default::default()
        },
    )
}

impl MiniUNet {
    /// Builds the reference's network (RGB input) under `root`, each layer on its own sub-path
    /// so names match the reference.
    pub fn new(root: &nn::Path) -> Self {
        Self::with_input(root, InputKind::Rgb)
    }

    /// The network for `input`: only the first convolution's input planes differ (3 or 4), so
    /// the parameter names stay the reference's and an rgb checkpoint is the reference's file.
    pub fn with_input(root: &nn::Path, input: InputKind) -> Self {
        Self {
            inc: conv(root / "inc" / "0", input.channels() as i64, 64, 3),
            down1: conv(root / "down1" / "1", 64, 128, 3),
            down2: conv(root / "down2" / "1", 128, 256, 3),
            upconv1: up(root / "upconv1", 256, 128),
            conv1: conv(root / "conv1" / "0", 256, 128, 3),
            upconv2: up(root / "upconv2", 128, 64),
            conv2: conv(root / "conv2" / "0", 128, 64, 3),
            outc: conv(root / "outc", 64, 1, 1),
        }
    }
}

/// Channels-last layout: tch has no memory-format API, so permute, copy, permute back.
pub(crate) fn channels_last(x: &Tensor) -> Tensor {
    x.permute([0, 2, 3, 1]).contiguous().permute([0, 3, 1, 2])
}

fn conv_bf16(x: &Tensor, conv: &nn::Conv2D) -> Tensor {
    let w = channels_last(&conv.ws.to_kind(Kind::BFloat16));
    let b = conv.bs.as_ref().map(|b| b.to_kind(Kind::BFloat16));
    let k = conv.ws.size()[2];
    x.conv2d(&w, b, [1, 1], [k / 2, k / 2], [1, 1], 1)
}

/// A float32 transposed convolution with its bias added as a separate broadcast, which gives
/// the same forward values: oneDNN computes a transposed convolution's bias gradient in its
/// scalar reference kernel, and ATen's reduction over the added bias is several times faster.
fn up_fp32(x: &Tensor, up: &nn::ConvTranspose2D) -> Tensor {
    let unbiased = x.conv_transpose2d::<Tensor>(&up.ws, None, [2, 2], [0, 0], [0, 0], 1, [1, 1]);
    match &up.bs {
        Some(b) => unbiased + b.view([1, -1, 1, 1]),
        None => unbiased,
    }
}

fn up_bf16(x: &Tensor, up: &nn::ConvTranspose2D) -> Tensor {
    let w = channels_last(&up.ws.to_kind(Kind::BFloat16));
    let b = up.bs.as_ref().map(|b| b.to_kind(Kind::BFloat16));
    x.conv_transpose2d(&w, b, [2, 2], [0, 0], [0, 0], 1, [1, 1])
}

impl MiniUNet {
    /// Logits, N×1×H×W float32, for an N×C×H×W input in [0, 1] (H and W divisible by 4),
    /// computed in `precision`: one graph, whose layers run as float32 modules or as bfloat16
    /// convolutions in channels_last.
    pub(crate) fn forward_with(&self, xs: &Tensor, precision: Precision) -> Tensor {
        let conv = |x: &Tensor, layer: &nn::Conv2D| match precision {
            Precision::Fp32 => x.apply(layer),
            Precision::Bf16 => conv_bf16(x, layer),
        };
        let up = |x: &Tensor, layer: &nn::ConvTranspose2D| match precision {
            Precision::Fp32 => up_fp32(x, layer),
            Precision::Bf16 => up_bf16(x, layer),
        };
        let x = match precision {
            Precision::Fp32 => xs.shallow_clone(),
            Precision::Bf16 => channels_last(&xs.to_kind(Kind::BFloat16)),
        }; // N×C×H×W
        let x1 = conv(&x, &self.inc).relu(); // N×64×H×W
        let x2 = conv(&x1.max_pool2d_default(2), &self.down1).relu(); // N×128×H/2×W/2
        let x3 = conv(&x2.max_pool2d_default(2), &self.down2).relu(); // N×256×H/4×W/4
        let u1 = up(&x3, &self.upconv1); // N×128×H/2×W/2
        let y1 = conv(&Tensor::cat(&[&u1, &x2], 1), &self.conv1).relu(); // N×128×H/2×W/2
        let u2 = up(&y1, &self.upconv2); // N×64×H×W
        let y2 = conv(&Tensor::cat(&[&u2, &x1], 1), &self.conv2).relu(); // N×64×H×W
        let logits = conv(&y2, &self.outc); // N×1×H×W
        match precision {
            Precision::Fp32 => logits,
            Precision::Bf16 => logits.to_kind(Kind::Float),
        }
    }
}

/// Floating-point operations (a multiply-add counts two) of one forward pass over an image of
/// `height` × `width` with `input` planes: the convolutions and transposed convolutions, which
/// are all but a fraction of a percent of the work. 6.6 GFLOP for an RGB 128 × 128 image.
pub(crate) fn forward_flops(input: i64, height: i64, width: i64) -> f64 {
    let pixels = |scale: i64| (height / scale * width / scale) as f64;
    let conv = |cin: i64, cout: i64, kernel: i64, scale: i64| {
        2.0 * (cin * cout * kernel * kernel) as f64 * pixels(scale)
    };
    // A 2 × 2 stride-2 transposed convolution touches each input pixel with all 4 taps.
    let up =
        |cin: i64, cout: i64, input_scale: i64| 2.0 * (cin * cout * 4) as f64 * pixels(input_scale);
    conv(input, 64, 3, 1)
        + conv(64, 128, 3, 2)
        + conv(128, 256, 3, 4)
        + up(256, 128, 4)
        + conv(256, 128, 3, 2)
        + up(128, 64, 2)
        + conv(128, 64, 3, 1)
        + conv(64, 1, 1, 1)
}

impl Module for MiniUNet {
    /// Logits, N×1×H×W, in float32.
    fn forward(&self, xs: &Tensor) -> Tensor {
        self.forward_with(xs, Precision::Fp32)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use tch::{Device, Kind};

    #[test]
    fn a_forward_pass_over_an_rgb_128_image_is_6_6_gflop() {
        let flops = forward_flops(3, 128, 128);
        assert!((flops / 1e9 - 6.635).abs() < 0.01, "{flops}");
        // Each halving of the image quarters the work.
        assert!((forward_flops(3, 64, 64) * 4.0 - flops).abs() < 1.0);
    }

    #[test]
    fn output_is_one_map_per_image_and_names_match_the_reference() {
        tch::manual_seed(0);
        let vs = nn::VarStore::new(Device::Cpu);
        let net = MiniUNet::new(&vs.root());
        let out = net.forward(&Tensor::rand([2, 3, 32, 48], (Kind::Float, Device::Cpu)));
        assert_eq!(out.size(), [2, 1, 32, 48]);
        let mut names: Vec<String> = vs.variables().into_keys().collect();
        names.sort();
        let mut expected: Vec<String> = PARAMETER_NAMES.iter().map(|s| s.to_string()).collect();
        expected.sort();
        assert_eq!(names, expected);
        let shapes = vs.variables();
        assert_eq!(shapes["upconv1.weight"].size(), [256, 128, 2, 2]);
        assert_eq!(shapes["conv1.0.weight"].size(), [128, 256, 3, 3]);
        assert_eq!(shapes["outc.weight"].size(), [1, 64, 1, 1]);
    }

    #[test]
    fn bf16_forward_agrees_with_fp32_and_trains_the_fp32_weights() {
        tch::manual_seed(2);
        let vs = nn::VarStore::new(Device::Cpu);
        let net = MiniUNet::new(&vs.root());
        let x = Tensor::rand([2, 3, 32, 32], (Kind::Float, Device::Cpu));
        let full = net.forward_with(&x, Precision::Fp32);
        let half = net.forward_with(&x, Precision::Bf16);
        assert_eq!(half.kind(), Kind::Float);
        assert_eq!(half.size(), full.size());
        let diff = (&full - &half).abs().max().double_value(&[]);
        let scale = full.abs().max().double_value(&[]);
        assert!(
            diff < 0.05 * scale + 1e-3,
            "bf16 differs by {diff} (scale {scale})"
        );
        half.sum(Kind::Float).backward();
        let grad = vs.variables()["inc.0.weight"].grad();
        assert_eq!(grad.kind(), Kind::Float);
        assert!(grad.abs().sum(Kind::Float).double_value(&[]) > 0.0);
    }

    #[test]
    fn initialisation_follows_pytorch_bounds() {
        tch::manual_seed(1);
        let vs = nn::VarStore::new(Device::Cpu);
        let _net = MiniUNet::new(&vs.root());
        let vars = vs.variables();
        let max = |name: &str| vars[name].abs().max().double_value(&[]);
        let bound = 1.0 / ((256 * 9) as f64).sqrt();
        assert!(max("conv1.0.weight") <= bound + 1e-7);
        assert!(max("conv1.0.weight") > bound * 0.9);
    }
}
