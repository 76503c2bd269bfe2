// The random layout of The Next Week's final_scene(), as the book's own program draws it:
// glibc's rand() in its start-up state (as after srand(1)), the 400 box heights
// random_double(1, 101) in the book's loop order (i then j), the Perlin tables of
// noise_texture(0.2) (drawn, not printed: they come between), then the 1,000 cloud centres
// point3::random(0, 165). book-anchor builds final_scene() from the same draws. Prints
// `h Y1` per box and `c X Y Z` per sphere, in the order rtow's nw-final lists its boxes and
// its group's spheres, to write the book's layout into a scene file exported from nw-final
// (docs/books.md, "The Cornell smoke and the final scene").
//
//   book-final-layout > layout.txt
#include "rtweekend.h"

#include "perlin.h"

#include <cstdio>

int main() {
    std::srand(1);
    for (int i = 0; i < 20; i++)
        for (int j = 0; j < 20; j++)
            std::printf("h %.17g\n", random_double(1, 101));
    perlin noise; // noise_texture(0.2)'s lattice, drawn between the boxes and the cloud
    (void)noise;
    for (int j = 0; j < 1000; j++) {
        auto c = point3::random(0, 165);
        std::printf("c %.17g %.17g %.17g\n", c.x(), c.y(), c.z());
    }
    return 0;
}
