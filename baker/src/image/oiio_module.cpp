// liblodbake_oiio: every OpenImageIO call of the baker (loaded on demand, see oiio_module.h). It reads
// PNG and JPEG bytes into their stored sample type and writes pixels back; the filtering is the
// library's (texture_pyramid.cpp).
#include "image/oiio_module.h"

#include <algorithm>
#include <exception>
#include <memory>

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>

namespace {

using lodbake::oiio_module::Codec;
using lodbake::oiio_module::Pixels;

// A file name whose extension makes OpenImageIO pick the right codec; the bytes come from memory.
const char* codecName(const uint8_t* b, size_t size) {
    if (size >= 8 && b[0] == 0x89 && b[1] == 'P' && b[2] == 'N' && b[3] == 'G') return "texture.png";
    if (size >= 3 && b[0] == 0xFF && b[1] == 0xD8 && b[2] == 0xFF) return "texture.jpg";
    return nullptr;
}

bool fail(std::string* error, const std::string& message) {
    *error = message;
    return false;
}

std::string oneLine(std::string why) {
    std::replace(why.begin(), why.end(), '\n', ' '); // messages are one line
    return why;
}

// OpenImageIO works on the caller's thread only: the baker parallelises itself, and no pool threads
// are left running when the process exits. Set once, when the module is first used.
void configureOnce() {
    static const bool configured = [] {
        OIIO::attribute("threads", 1);
        return true;
    }();
    (void)configured;
}

// An ImageInput reading the encoded bytes from memory (no file, no ImageCache: an ImageBuf opened by
// name would go through the process-wide cache, where every texture is "texture.png" and the memory
// reader of an earlier call may be looked up after it is gone).
bool openInput(const char* codec, OIIO::Filesystem::IOMemReader* reader, std::unique_ptr<OIIO::ImageInput>* input,
               std::string* error) {
    configureOnce();
    OIIO::ImageSpec config;
    void* proxy = reader;
    config.attribute("oiio:ioproxy", OIIO::TypeDesc::PTR, &proxy);
    // Samples as stored: OpenImageIO would otherwise premultiply colour by alpha on reading.
    config.attribute("oiio:UnassociatedAlpha", 1);
    *input = OIIO::ImageInput::open(codec, &config);
    if (!*input) return fail(error, "cannot read the image header: " + oneLine(OIIO::geterror()));
    return true;
}

bool decodeImpl(const uint8_t* data, size_t size, Pixels* out, std::string* error) {
    const char* codec = codecName(data, size);
    if (!codec) return fail(error, "not a PNG or JPEG image");
    OIIO::Filesystem::IOMemReader reader(const_cast<uint8_t*>(data), size);
    std::unique_ptr<OIIO::ImageInput> input;
    if (!openInput(codec, &reader, &input, error)) return false;
    const OIIO::ImageSpec& spec = input->spec();
    if (spec.width <= 0 || spec.height <= 0 || spec.nchannels <= 0 || spec.nchannels > 4)
        return fail(error, "expected 1 to 4 channels and a width and height above 0");
    const bool is_16 = spec.format == OIIO::TypeDesc::UINT16;
    out->width = uint32_t(spec.width);
    out->height = uint32_t(spec.height);
    out->channels = uint32_t(spec.nchannels);
    out->bits = is_16 ? 16 : 8;
    out->data.assign(size_t(out->width) * out->height * out->channels * (is_16 ? 2 : 1), 0);
    const OIIO::TypeDesc type = is_16 ? OIIO::TypeDesc::UINT16 : OIIO::TypeDesc::UINT8;
    // libjpeg (and libpng for some damage) reports a truncated or corrupt stream as a warning and
    // fills the missing pixels with grey; OpenImageIO records the warning but read_image succeeds.
    // A damaged texture must fail the bake, not become a partly grey level, so any error counts.
    const bool is_read = input->read_image(0, 0, 0, spec.nchannels, type, out->data.data());
    if (!is_read || input->has_error()) {
        const std::string why = oneLine(input->geterror());
        return fail(error, "cannot decode the image: " + (why.empty() ? std::string("read failed") : why));
    }
    input->close();
    return true;
}

bool decode(const uint8_t* data, size_t size, Pixels* out, std::string* error) {
    try {
        return decodeImpl(data, size, out, error);
    } catch (const std::exception& e) {
        return fail(error, std::string("image decoding failed: ") + e.what());
    }
}

bool encodeImpl(const Pixels& pixels, Codec codec, int jpeg_quality, std::vector<uint8_t>* out, std::string* error) {
    configureOnce();
    const bool is_jpeg = codec == Codec::Jpeg;
    if (is_jpeg && pixels.bits != 8) return fail(error, "a JPEG level must have 8-bit samples");
    const char* name = is_jpeg ? "texture.jpg" : "texture.png";
    const OIIO::TypeDesc type = pixels.bits == 16 ? OIIO::TypeDesc::UINT16 : OIIO::TypeDesc::UINT8;
    // Only the pixel layout is written: no timestamps or software tags (STYLE.md §7).
    OIIO::ImageSpec spec(int(pixels.width), int(pixels.height), int(pixels.channels), type);
    if (is_jpeg) spec.attribute("Compression", "jpeg:" + std::to_string(std::min(std::max(jpeg_quality, 1), 100)));
    spec.attribute("oiio:UnassociatedAlpha", 1); // the samples are stored as they are, not divided by alpha
    std::vector<unsigned char> bytes;
    OIIO::Filesystem::IOVecOutput writer(bytes);
    auto output = OIIO::ImageOutput::create(name);
    if (!output) return fail(error, std::string("no encoder for ") + name);
    if (!output->set_ioproxy(&writer)) return fail(error, "the encoder cannot write to memory");
    if (!output->open(name, spec) || !output->write_image(type, pixels.data.data()) || !output->close())
        return fail(error, "encoding failed: " + oneLine(output->geterror()));
    out->assign(bytes.begin(), bytes.end());
    return true;
}

bool encode(const Pixels& pixels, Codec codec, int jpeg_quality, std::vector<uint8_t>* out, std::string* error) {
    try {
        return encodeImpl(pixels, codec, jpeg_quality, out, error);
    } catch (const std::exception& e) {
        return fail(error, std::string("image encoding failed: ") + e.what());
    }
}

bool probe(const uint8_t* data, size_t size, uint32_t* width, uint32_t* height, std::string* error) {
    const char* codec = codecName(data, size);
    if (!codec) return fail(error, "not a PNG or JPEG image");
    try {
        OIIO::Filesystem::IOMemReader reader(const_cast<uint8_t*>(data), size);
        std::unique_ptr<OIIO::ImageInput> input;
        if (!openInput(codec, &reader, &input, error)) return false;
        const OIIO::ImageSpec& spec = input->spec();
        if (spec.width <= 0 || spec.height <= 0) return fail(error, "image has no pixels");
        *width = uint32_t(spec.width);
        *height = uint32_t(spec.height);
        return true;
    } catch (const std::exception& e) {
        return fail(error, e.what());
    }
}

const lodbake::oiio_module::Api kApi{lodbake::oiio_module::kApiVersion, probe, decode, encode};

} // namespace

extern "C" __attribute__((visibility("default"))) const lodbake::oiio_module::Api* lodbake_oiio_api() {
    return &kApi;
}
