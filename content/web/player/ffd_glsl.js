// The FFD as PlayCanvas's gsplat shader hook (chunk "gsplatModifyVS", GLSL ES 3.0): a port of
// shaders/ffd/ffd_common.glsl (displacement form X' = X + D(X), J = I + G M^-1) and of the Gaussian
// deformation in shaders/gaussian/deform.comp (Sigma' = J Sigma J^T = A A^T with A = J R S, A's columns
// orthogonalised by one-sided Jacobi into rotation + scale). PlayCanvas 2.23 hands the hook the centre
// (modifySplatCenter) and then the rotation and scale (modifySplatRotationScale), not the covariance, so
// J Sigma J^T goes back as a rotation and three scales, exactly as our own GPU pass stores it.
// Control points arrive as displacements Delta P (pose - rest) in an RGBA32F texture, 64 texels a row,
// flat index (i*(m+1)+j)*(n+1)+k; the B-spline's zero border is a bounds test instead of padding.
// Points outside the lattice (beyond 1e-6 in local coordinates) stay put, as in our shaders.
window.SFFD_FFD_GLSL = `
uniform highp sampler2D uFfdPoints;
uniform vec3 uFfdMinv0;
uniform vec3 uFfdMinv1;
uniform vec3 uFfdMinv2;
uniform vec3 uFfdOrigin;
uniform vec4 uFfdDiv;

#define FFD_MAX_B 12
const float FFD_SLACK = 1e-6;

mat3 ffdJ = mat3(1.0);
bool ffdMoved = false;

vec3 ffdDp(int i) {
    return texelFetch(uFfdPoints, ivec2(i % 64, i / 64), 0).xyz;
}

void ffdBernstein(float s, int L, out float b[FFD_MAX_B], out float db[FFD_MAX_B]) {
    float r = 1.0 - s;
    float sp[FFD_MAX_B], rp[FFD_MAX_B];
    sp[0] = 1.0;
    rp[0] = 1.0;
    for (int i = 1; i < FFD_MAX_B; ++i) {
        if (i > L) break;
        sp[i] = sp[i - 1] * s;
        rp[i] = rp[i - 1] * r;
    }
    float c = 1.0, c1 = 1.0;
    float prev = 0.0;
    float fl = float(L);
    for (int i = 0; i < FFD_MAX_B; ++i) {
        if (i > L) { b[i] = 0.0; db[i] = 0.0; continue; }
        b[i] = c * sp[i] * rp[L - i];
        float cur = i <= L - 1 ? c1 * sp[i] * rp[max(L - 1 - i, 0)] : 0.0;
        db[i] = fl * (prev - cur);
        prev = cur;
        c = c * float(L - i) / float(i + 1);
        c1 = c1 * float(L - 1 - i) / float(i + 1);
    }
}

void ffdBsplineWeights(float f, float n, out vec4 w, out vec4 dw) {
    float f2 = f * f, f3 = f2 * f, r = 1.0 - f;
    w = vec4(r * r * r, 3.0 * f3 - 6.0 * f2 + 4.0, -3.0 * f3 + 3.0 * f2 + 3.0 * f + 1.0, f3) / 6.0;
    dw = vec4(-0.5 * r * r, 1.5 * f2 - 2.0 * f, -1.5 * f2 + f + 0.5, 0.5 * f2) * n;
}

void ffdEval(vec3 stu, out vec3 D, out mat3 G) {
    stu = clamp(stu, vec3(0.0), vec3(1.0));
    int L = int(uFfdDiv.x), M = int(uFfdDiv.y), N = int(uFfdDiv.z);
    D = vec3(0.0);
    vec3 Fs = vec3(0.0), Ft = vec3(0.0), Fu = vec3(0.0);
    if (uFfdDiv.w < 0.5) {
        float bs[FFD_MAX_B], dbs[FFD_MAX_B], bt[FFD_MAX_B], dbt[FFD_MAX_B], bu[FFD_MAX_B], dbu[FFD_MAX_B];
        ffdBernstein(stu.x, L, bs, dbs);
        ffdBernstein(stu.y, M, bt, dbt);
        ffdBernstein(stu.z, N, bu, dbu);
        for (int i = 0; i <= L; ++i) {
            vec3 R = vec3(0.0), Rt = vec3(0.0), Ru = vec3(0.0);
            for (int j = 0; j <= M; ++j) {
                int base = (i * (M + 1) + j) * (N + 1);
                vec3 q = vec3(0.0), w = vec3(0.0);
                for (int k = 0; k <= N; ++k) {
                    vec3 d = ffdDp(base + k);
                    q += bu[k] * d;
                    w += dbu[k] * d;
                }
                R += q * bt[j];
                Rt += q * dbt[j];
                Ru += w * bt[j];
            }
            D += R * bs[i];
            Fs += R * dbs[i];
            Ft += Rt * bs[i];
            Fu += Ru * bs[i];
        }
    } else {
        vec3 g = stu * vec3(L, M, N);
        ivec3 c = min(ivec3(g), ivec3(L, M, N) - 1);
        vec3 f = g - vec3(c);
        vec4 ws, dws, wt, dwt, wu, dwu;
        ffdBsplineWeights(f.x, float(L), ws, dws);
        ffdBsplineWeights(f.y, float(M), wt, dwt);
        ffdBsplineWeights(f.z, float(N), wu, dwu);
        for (int a = 0; a < 4; ++a) {
            int i = c.x + a - 1;
            if (i < 0 || i > L) continue;
            for (int b = 0; b < 4; ++b) {
                int j = c.y + b - 1;
                if (j < 0 || j > M) continue;
                vec3 q = vec3(0.0), w = vec3(0.0);
                for (int k = 0; k < 4; ++k) {
                    int kk = c.z + k - 1;
                    if (kk < 0 || kk > N) continue;
                    vec3 d = ffdDp((i * (M + 1) + j) * (N + 1) + kk);
                    q += wu[k] * d;
                    w += dwu[k] * d;
                }
                D += q * (ws[a] * wt[b]);
                Fs += q * (dws[a] * wt[b]);
                Ft += q * (ws[a] * dwt[b]);
                Fu += w * (ws[a] * wt[b]);
            }
        }
    }
    G = mat3(Fs, Ft, Fu);
}

void ffdOrthogonalise(inout vec3 bp, inout vec3 bq) {
    float alpha = dot(bp, bp), beta = dot(bq, bq), gamma = dot(bp, bq);
    if (!(abs(gamma) > 1e-7 * sqrt(alpha * beta)) || gamma == 0.0) return;
    float d = beta - alpha, g = 2.0 * gamma;
    float m = max(abs(d), abs(g));
    d /= m;
    g /= m;
    float rr = inversesqrt(d * d + g * g);
    float cos2 = abs(d) * rr, sin2 = (d < 0.0 ? -g : g) * rr;
    float h = 0.5 + 0.5 * cos2, rh = inversesqrt(h);
    float c = h * rh, s = (0.5 * sin2) * rh;
    vec3 np = c * bp - s * bq;
    vec3 nq = s * bp + c * bq;
    bp = np;
    bq = nq;
}

// Axes (columns, a proper rotation) and scales of A A^T (deform.comp's decompose()).
void ffdDecompose(mat3 a, out mat3 axes, out vec3 scale) {
    vec3 b0 = a[0], b1 = a[1], b2 = a[2];
    for (int sweep = 0; sweep < 12; ++sweep) {
        float n0 = dot(b0, b0), n1 = dot(b1, b1), n2 = dot(b2, b2);
        float off = max(max(abs(dot(b0, b1)) * inversesqrt(max(n0 * n1, 1e-37)),
                            abs(dot(b0, b2)) * inversesqrt(max(n0 * n2, 1e-37))),
                        abs(dot(b1, b2)) * inversesqrt(max(n1 * n2, 1e-37)));
        if (!(off > 1e-7)) break;
        ffdOrthogonalise(b0, b1);
        ffdOrthogonalise(b0, b2);
        ffdOrthogonalise(b1, b2);
    }
    vec3 s = vec3(length(b0), length(b1), length(b2));
    if (s.y > s.x) { vec3 t = b0; b0 = b1; b1 = t; s.xy = s.yx; }
    if (s.z > s.y) { vec3 t = b1; b1 = b2; b2 = t; s.yz = s.zy; }
    if (s.y > s.x) { vec3 t = b0; b0 = b1; b1 = t; s.xy = s.yx; }
    float tiny = 1e-6 * s.x;
    vec3 u0 = s.x > 0.0 ? b0 / s.x : vec3(1.0, 0.0, 0.0);
    vec3 u1;
    if (s.y > tiny) {
        u1 = b1 / s.y;
    } else {
        vec3 other = abs(u0.x) < 0.9 ? vec3(1.0, 0.0, 0.0) : vec3(0.0, 1.0, 0.0);
        u1 = normalize(cross(u0, other));
    }
    u1 = normalize(u1 - dot(u0, u1) * u0);
    vec3 u2 = cross(u0, u1);
    axes = mat3(u0, u1, u2);
    scale = s;
}

// Unit quaternion (x, y, z, w), w >= 0, of a rotation matrix (Shepperd), the hook's layout.
vec4 ffdMat3ToQuat(mat3 m) {
    float tr = m[0][0] + m[1][1] + m[2][2];
    vec4 q;  // (w, x, y, z)
    if (tr > 0.0) {
        float s = sqrt(tr + 1.0) * 2.0;
        q = vec4(0.25 * s, (m[1][2] - m[2][1]) / s, (m[2][0] - m[0][2]) / s, (m[0][1] - m[1][0]) / s);
    } else if (m[0][0] > m[1][1] && m[0][0] > m[2][2]) {
        float s = sqrt(1.0 + m[0][0] - m[1][1] - m[2][2]) * 2.0;
        q = vec4((m[1][2] - m[2][1]) / s, 0.25 * s, (m[1][0] + m[0][1]) / s, (m[2][0] + m[0][2]) / s);
    } else if (m[1][1] > m[2][2]) {
        float s = sqrt(1.0 + m[1][1] - m[0][0] - m[2][2]) * 2.0;
        q = vec4((m[2][0] - m[0][2]) / s, (m[1][0] + m[0][1]) / s, 0.25 * s, (m[2][1] + m[1][2]) / s);
    } else {
        float s = sqrt(1.0 + m[2][2] - m[0][0] - m[1][1]) * 2.0;
        q = vec4((m[0][1] - m[1][0]) / s, (m[2][0] + m[0][2]) / s, (m[2][1] + m[1][2]) / s, 0.25 * s);
    }
    q = normalize(q);
    if (q.x < 0.0) q = -q;
    return q.yzwx;
}

mat3 ffdQuatToMat3(vec4 q) {  // (x, y, z, w)
    q = normalize(q);
    float x = q.x, y = q.y, z = q.z, w = q.w;
    return mat3(1.0 - 2.0 * (y * y + z * z), 2.0 * (x * y + w * z), 2.0 * (x * z - w * y),
                2.0 * (x * y - w * z), 1.0 - 2.0 * (x * x + z * z), 2.0 * (y * z + w * x),
                2.0 * (x * z + w * y), 2.0 * (y * z - w * x), 1.0 - 2.0 * (x * x + y * y));
}

void modifySplatCenter(inout vec3 center) {
    ffdMoved = false;
    ffdJ = mat3(1.0);
    vec3 p = center - uFfdOrigin;
    vec3 stu = vec3(dot(uFfdMinv0, p), dot(uFfdMinv1, p), dot(uFfdMinv2, p));
    if (any(lessThan(stu, vec3(-FFD_SLACK))) || any(greaterThan(stu, vec3(1.0 + FFD_SLACK)))) return;
    vec3 D;
    mat3 G;
    ffdEval(stu, D, G);
    mat3 minv = transpose(mat3(uFfdMinv0, uFfdMinv1, uFfdMinv2));
    ffdJ = mat3(1.0) + G * minv;
    ffdMoved = true;
    center += D;
}

void modifySplatRotationScale(vec3 originalCenter, vec3 modifiedCenter, inout vec4 rotation, inout vec3 scale) {
    if (!ffdMoved || ffdJ == mat3(1.0)) return;
    mat3 rq = ffdQuatToMat3(rotation);
    mat3 a = ffdJ * mat3(rq[0] * scale.x, rq[1] * scale.y, rq[2] * scale.z);
    float m = 0.0;
    for (int c = 0; c < 3; ++c) m = max(m, max(max(abs(a[c].x), abs(a[c].y)), abs(a[c].z)));
    if (!(m > 0.0)) { scale = vec3(0.0); return; }
    mat3 axes;
    vec3 s;
    ffdDecompose(a * (1.0 / m), axes, s);
    rotation = ffdMat3ToQuat(axes);
    scale = s * m;
}

void modifySplatColor(vec3 center, inout vec4 color) {
}
`;
