// C's printf number formats as glibc writes them, exactly: "%.Nf" and
// "%.Pg" from the double's exact decimal value, ties to even. The map
// writer (server/sim/map/map_writer.cpp) uses "%.2f" for objects and
// "%.10g" for the tile size, and a saved map must be byte for byte what the
// daemon's WriteMap would write; JavaScript's toFixed rounds ties away from
// zero (0.125 -> "0.13", glibc "0.12"), so it is not used.

const mantissaBits = new BigUint64Array(1);
const asFloat = new Float64Array(mantissaBits.buffer);

// |value| as digits / 10^scale (BigInt digits, exact).
function exactDecimal(value) {
  asFloat[0] = Math.abs(value);
  const bits = mantissaBits[0];
  const biased = Number(bits >> 52n);
  let mantissa = bits & ((1n << 52n) - 1n);
  let exponent;
  if (biased === 0) exponent = -1074;  // subnormal
  else { mantissa |= 1n << 52n; exponent = biased - 1075; }
  if (exponent >= 0) return { digits: mantissa << BigInt(exponent), scale: 0 };
  return { digits: mantissa * 5n ** BigInt(-exponent), scale: -exponent };
}

// digits / 10^drop rounded to an integer, ties to even.
function roundDrop(digits, drop) {
  if (drop <= 0) return digits * 10n ** BigInt(-drop);
  const unit = 10n ** BigInt(drop);
  const quotient = digits / unit, rest = digits % unit, twice = rest * 2n;
  if (twice > unit || (twice === unit && quotient % 2n === 1n)) return quotient + 1n;
  return quotient;
}

function isNegative(value) {
  return value < 0 || Object.is(value, -0);
}

function special(value) {
  if (Number.isNaN(value)) return "nan";
  return value < 0 ? "-inf" : "inf";
}

// printf("%.<decimals>f", value).
export function formatFixed(value, decimals) {
  if (!Number.isFinite(value)) return special(value);
  const { digits, scale } = exactDecimal(value);
  let text = roundDrop(digits, scale - decimals).toString();
  if (decimals > 0) {
    text = text.padStart(decimals + 1, "0");
    text = `${text.slice(0, -decimals)}.${text.slice(-decimals)}`;
  }
  return (isNegative(value) ? "-" : "") + text;
}

function stripZeros(text) {
  return text.includes(".") ? text.replace(/0+$/, "").replace(/\.$/, "") : text;
}

// printf("%.<precision>g", value).
export function formatGeneral(value, precision = 6) {
  if (!Number.isFinite(value)) return special(value);
  const sign = isNegative(value) ? "-" : "";
  const p = Math.max(1, precision);
  if (value === 0) return `${sign}0`;
  const { digits, scale } = exactDecimal(value);
  const length = digits.toString().length;
  let exponent = length - 1 - scale;  // value = d.ddd x 10^exponent
  let rounded = roundDrop(digits, length - p);
  if (rounded.toString().length > p) {  // 9.99.. rounded up to 10.0..
    rounded /= 10n;
    exponent += 1;
  }
  const text = rounded.toString();
  if (exponent < -4 || exponent >= p) {
    const mantissa = stripZeros(text.length > 1 ? `${text[0]}.${text.slice(1)}` : text);
    const e = Math.abs(exponent).toString().padStart(2, "0");
    return `${sign}${mantissa}e${exponent < 0 ? "-" : "+"}${e}`;
  }
  if (exponent >= 0) {
    const whole = text.slice(0, exponent + 1), fraction = text.slice(exponent + 1);
    return sign + stripZeros(fraction ? `${whole}.${fraction}` : whole);
  }
  return sign + stripZeros(`0.${"0".repeat(-exponent - 1)}${text}`);
}
