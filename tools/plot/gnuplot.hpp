// Drives gnuplot (Debian package gnuplot-nox), the plotting tool behind `./rover plot` and
// vo_eval's trajectory.png: a picture is a data file and a script, both kept beside the
// picture so that anyone can re-run or edit them (`cd DIR/plot && gnuplot traverse.gp`).
#pragma once

#include <cstddef>
#include <string>
#include <vector>

namespace rover::plot {

// The PNG terminal to use: "pngcairo" (antialiased) when this gnuplot has it, else "png";
// empty when gnuplot cannot be run at all.
std::string PngTerminal();

// Runs `gnuplot SCRIPT` in `workdir` (scripts name their files relative to it); gnuplot's
// messages go to SCRIPT with .log in place of .gp. Returns "" or a one-line reason, with
// gnuplot's first error line when it gave one.
std::string RunGnuplot(const std::string& workdir, const std::string& script);

// A gnuplot string literal: double quotes, with \\, \" and \n escaped (so a title may hold
// a line break).
std::string Quoted(const std::string& text);

// `text` with each of its lines broken into lines of at most `max_chars` characters, so a
// long title (a log with several sequences) is shown whole instead of cut at the picture's
// edges. A line breaks after "; " where it can, else after ", ", else at a space; a word
// longer than a line stays whole.
std::string WrapTitle(const std::string& text, std::size_t max_chars);

// The characters of a title line that fit `width_px` in the pictures' font, with a margin
// (sans 10 on pngcairo: about 137 characters of a title filled 900 px, 6.6 px each; a line
// is given 7 px a character).
std::size_t TitleChars(int width_px);

// A number as gnuplot reads it ("?" for a missing value: scripts set datafile missing).
std::string Num(double v);

}  // namespace rover::plot
