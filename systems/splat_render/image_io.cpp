// PNG through libpng's simplified API, EXR through OpenEXR's scanline API into memory, then an atomic save.
#include "systems/splat_render/image_io.h"

#include <png.h>

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfIO.h>
#include <ImfInputFile.h>
#include <ImfOutputFile.h>
#include <ImfStringAttribute.h>
#include <half.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <exception>
#include <limits>
#include <string>

#include "runtime/core/atomic_file.h"
#include "runtime/gfx/splat_pack.h"

namespace sffd::render {

float linear_to_srgb(float c) {
    c = std::clamp(c, 0.0f, 1.0f);
    return c <= 0.0031308f ? 12.92f * c : 1.055f * std::pow(c, 1.0f / 2.4f) - 0.055f;
}

float srgb_to_linear(float c) {
    c = std::clamp(c, 0.0f, 1.0f);
    return c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f);
}

std::uint8_t encode_srgb8(float linear) { return gfx::encode_srgb8(linear); }

Rgba8Image to_rgba8(const FrameImage& image, std::optional<glm::vec3> background) {
    Rgba8Image out{image.width, image.height, {}};
    out.pixels.resize(std::size_t(image.width) * std::size_t(image.height) * 4);
    for (std::size_t i = 0; i < image.color.size(); ++i) {
        const glm::vec4 c = image.color[i];
        std::uint8_t* p = &out.pixels[i * 4];
        const float a = std::clamp(c.w, 0.0f, 1.0f);
        if (background && a < 1.0f) {
            // Over a background the straight colour is blended in display (sRGB) space, as 3DGS viewers and
            // the
            // --video path do: blending in linear space made soft edges lighter on dark backgrounds.
            for (int k = 0; k < 3; ++k) {
                const float v = linear_to_srgb(c[k]) * a + linear_to_srgb((*background)[k]) * (1.0f - a);
                p[k] = static_cast<std::uint8_t>(std::lround(std::clamp(v, 0.0f, 1.0f) * 255.0f));
            }
            p[3] = 255;
            continue;
        }
        p[0] = encode_srgb8(c.x);
        p[1] = encode_srgb8(c.y);
        p[2] = encode_srgb8(c.z);
        p[3] = background ? 255 : static_cast<std::uint8_t>(std::lround(a * 255.0f));
    }
    return out;
}

Status write_png(const std::filesystem::path& path, const Rgba8Image& image) {
    if (image.width <= 0 || image.height <= 0 ||
        image.pixels.size() != std::size_t(image.width) * image.height * 4)
        return make_error(path.string() + ": write_png(): empty or inconsistent image");
    png_image png;
    std::memset(&png, 0, sizeof png);
    png.version = PNG_IMAGE_VERSION;
    png.width = static_cast<png_uint_32>(image.width);
    png.height = static_cast<png_uint_32>(image.height);
    png.format = PNG_FORMAT_RGBA;
    png_alloc_size_t bytes = 0;
    if (!png_image_write_to_memory(&png, nullptr, &bytes, 0, image.pixels.data(), 0, nullptr))
        return make_error(path.string() + ": libpng: " + png.message);
    std::string buffer(bytes, '\0');
    if (!png_image_write_to_memory(&png, buffer.data(), &bytes, 0, image.pixels.data(), 0, nullptr))
        return make_error(path.string() + ": libpng: " + png.message);
    buffer.resize(bytes);
    return write_file_atomic(path, buffer);
}

Result<Rgba8Image> read_png(const std::filesystem::path& path) {
    png_image png;
    std::memset(&png, 0, sizeof png);
    png.version = PNG_IMAGE_VERSION;
    if (!png_image_begin_read_from_file(&png, path.c_str()))
        return make_error(path.string() + ": not a readable PNG (" + png.message + ")");
    png.format = PNG_FORMAT_RGBA;
    Rgba8Image out{static_cast<int>(png.width), static_cast<int>(png.height), {}};
    out.pixels.resize(PNG_IMAGE_SIZE(png));
    if (!png_image_finish_read(&png, nullptr, out.pixels.data(), 0, nullptr)) {
        std::string message = png.message;
        png_image_free(&png);
        return make_error(path.string() + ": corrupt PNG (" + message + ")");
    }
    return out;
}

namespace {

// OpenEXR writes through a seekable stream; keep the whole file in memory, then save atomically.
class MemoryOStream final : public Imf::OStream {
public:
    MemoryOStream() : Imf::OStream("memory") {}
    void write(const char c[], int n) override {
        const std::size_t end = m_pos + std::size_t(n);
        if (end > m_data.size()) m_data.resize(end);
        std::memcpy(m_data.data() + m_pos, c, std::size_t(n));
        m_pos = end;
    }
    uint64_t tellp() override { return m_pos; }
    void seekp(uint64_t pos) override { m_pos = pos; }
    const std::string& data() const { return m_data; }

private:
    std::string m_data;
    std::size_t m_pos = 0;
};

}  // namespace

Status write_exr(const std::filesystem::path& path, const FrameImage& image) {
    const std::size_t n = std::size_t(image.width) * std::size_t(image.height);
    if (image.width <= 0 || image.height <= 0 || image.color.size() != n)
        return make_error(path.string() + ": write_exr(): empty or inconsistent image");
    const bool has_z = image.depth.size() == n;
    const bool has_n = image.normal.size() == n;
    // Planar half/float copies: OpenEXR reads through strided slices.
    std::vector<half> rgba(n * 4), normals(has_n ? n * 3 : 0);
    for (std::size_t i = 0; i < n; ++i)
        for (int c = 0; c < 4; ++c) rgba[i * 4 + std::size_t(c)] = half(image.color[i][c]);
    for (std::size_t i = 0; i < normals.size() / 3; ++i)
        for (int c = 0; c < 3; ++c) normals[i * 3 + std::size_t(c)] = half(image.normal[i][c]);
    try {
        Imf::Header header(image.width, image.height);
        header.compression() = Imf::ZIP_COMPRESSION;
        header.insert("software", Imf::StringAttribute("splatffd " SFFD_VERSION));
        Imf::ChannelList& channels = header.channels();
        Imf::FrameBuffer fb;
        const char* rgba_names[4] = {"R", "G", "B", "A"};
        for (int c = 0; c < 4; ++c) {
            channels.insert(rgba_names[c], Imf::Channel(Imf::HALF));
            fb.insert(rgba_names[c],
                      Imf::Slice(Imf::HALF, reinterpret_cast<char*>(&rgba[std::size_t(c)]), sizeof(half) * 4,
                                 sizeof(half) * 4 * std::size_t(image.width)));
        }
        if (has_z) {
            channels.insert("Z", Imf::Channel(Imf::FLOAT));
            fb.insert("Z",
                      Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(const_cast<float*>(image.depth.data())),
                                 sizeof(float), sizeof(float) * std::size_t(image.width)));
        }
        if (has_n) {
            const char* n_names[3] = {"N.X", "N.Y", "N.Z"};
            for (int c = 0; c < 3; ++c) {
                channels.insert(n_names[c], Imf::Channel(Imf::HALF));
                fb.insert(n_names[c],
                          Imf::Slice(Imf::HALF, reinterpret_cast<char*>(&normals[std::size_t(c)]),
                                     sizeof(half) * 3, sizeof(half) * 3 * std::size_t(image.width)));
            }
        }
        MemoryOStream stream;
        {
            Imf::OutputFile file(stream, header);
            file.setFrameBuffer(fb);
            file.writePixels(image.height);
        }
        return write_file_atomic(path, stream.data());
    } catch (const std::exception& e) {
        return make_error(path.string() + ": OpenEXR: " + e.what());
    }
}

Result<FrameImage> read_exr(const std::filesystem::path& path) {
    try {
        Imf::InputFile file(path.c_str());
        const Imath::Box2i dw = file.header().dataWindow();
        FrameImage out;
        out.width = dw.max.x - dw.min.x + 1;
        out.height = dw.max.y - dw.min.y + 1;
        const std::size_t n = std::size_t(out.width) * std::size_t(out.height);
        const Imf::ChannelList& channels = file.header().channels();
        std::vector<float> rgba(n * 4, 0.0f), normals(n * 3, 0.0f);
        for (std::size_t i = 0; i < n; ++i) rgba[i * 4 + 3] = 1.0f;
        const bool has_z = channels.findChannel("Z") != nullptr;
        const bool has_n = channels.findChannel("N.X") != nullptr;
        if (has_z) out.depth.assign(n, 0.0f);
        // Slices are addressed relative to the data window's origin.
        const std::ptrdiff_t origin = std::ptrdiff_t(dw.min.y) * out.width + dw.min.x;
        Imf::FrameBuffer fb;
        const char* rgba_names[4] = {"R", "G", "B", "A"};
        for (int c = 0; c < 4; ++c)
            fb.insert(rgba_names[c],
                      Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(rgba.data() + c - origin * 4),
                                 sizeof(float) * 4, sizeof(float) * 4 * std::size_t(out.width), 1, 1,
                                 c == 3 ? 1.0 : 0.0));
        if (has_z)
            fb.insert("Z", Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(out.depth.data() - origin),
                                      sizeof(float), sizeof(float) * std::size_t(out.width)));
        const char* n_names[3] = {"N.X", "N.Y", "N.Z"};
        if (has_n)
            for (int c = 0; c < 3; ++c)
                fb.insert(n_names[c],
                          Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(normals.data() + c - origin * 3),
                                     sizeof(float) * 3, sizeof(float) * 3 * std::size_t(out.width)));
        file.setFrameBuffer(fb);
        file.readPixels(dw.min.y, dw.max.y);
        out.color.resize(n);
        for (std::size_t i = 0; i < n; ++i)
            out.color[i] = glm::vec4(rgba[i * 4], rgba[i * 4 + 1], rgba[i * 4 + 2], rgba[i * 4 + 3]);
        if (has_n) {
            out.normal.resize(n);
            for (std::size_t i = 0; i < n; ++i)
                out.normal[i] = glm::vec3(normals[i * 3], normals[i * 3 + 1], normals[i * 3 + 2]);
        }
        return out;
    } catch (const std::exception& e) {
        return make_error(path.string() + ": not a readable EXR (" + e.what() + ")");
    }
}

}  // namespace sffd::render
