/* golf: ref=psnr:29:golf/pt_ref.ppm in=golf/pt.sph */
/*! pt_card: path tracing (Kajiya 1986) on a card, reading the sphere format:
./a.out <golf/pt.sph >x.ppm    64x48, 512 paths a pixel, linear P3 as minray.
Camera: eye at the origin looking along +y, +z up, screen 64 pixels away
(ray.c: camera 0 0 0  0 1 0  0 0 1  53.13010235415598).  kd: Lambert, cosine
sampled; ks: mirror; kt: glass, Schlick's Fresnel; kl: emits to both sides.
A lobe is drawn with chance k/1.25; the rest ends the path (roulette).
Its reference is ray --pt at 16384 paths a pixel (golf/pt_ref.sh): 31.7 dB.
Made by golf/squeeze from golf/src/pt_card.c: edit that one. */
typedef struct{double x,y,z;}vec;vec U,O;struct sphere{vec cen,color;double rad,
kd,ks,kt,kl,ir;}*s,*best,sph[99];yx,n;unsigned long long S;double u,b,tmin,sqrt(
),pow();double R(){return((S=S*6364136223846793005+1)>>11)/9007199254740992.;}
double vdot(vec A,vec B){return A.x*B.x+A.y*B.y+A.z*B.z;}vec vcomb(double a,vec
A,vec B){B.x+=a*A.x;B.y+=a*A.y;B.z+=a*A.z;return B;}vec vunit(vec A){return
vcomb(1/sqrt(vdot(A,A)),A,O);}struct sphere*intersect(vec P,vec D){best=0;tmin=
1e30;s=sph+n;while(s-->sph)b=vdot(D,U=vcomb(-1,P,s->cen)),u=b*b-vdot(U,U)+s->rad
*s->rad,u=u>0?sqrt(u):1e31,u=b-u>1e-7?b-u:b+u,tmin=u>=1e-7&&u<tmin?best=s,u:tmin
;return best;}vec trace(vec P,vec D){double u=R()*1.25,d,e,c;vec N,E,W={1,1,1};
struct sphere*s=intersect(P,D);if(!s)return O;E=vcomb(s->kl,s->color,O);d=-vdot(
D,N=vunit(vcomb(-1,s->cen,P=vcomb(tmin,D,P))));e=1/s->ir;if(d<0)N=vcomb(-1,N,O),
d=-d,e=s->ir;if((u-=s->kd)<0){do U.x=2*R()-1,U.y=2*R()-1,U.z=2*R()-1;while(vdot(
U,U)>1);D=vunit(vcomb(1,vunit(U),N));W=s->color;}else if((u-=s->ks)<0)D=vcomb(2*
d,N,D);else if((u-=s->kt)<0){c=1-e*e*(1-d*d);b=(1-s->ir)/(1+s->ir);b*=b;D=c>0&&R
()>b+(1-b)*pow(1-(d<(c=sqrt(c))?d:c),5.)?vcomb(e,D,vcomb(e*d-c,N,O)):vcomb(2*d,N
,D);}else return E;D=trace(P,D);D.x*=W.x;D.y*=W.y;D.z*=W.z;return vcomb(1.25,D,E
);}double q(double v){return v<1?v*255:255;}main(){char l[999],*p;int k,c;double
*d;vec A;while(*l=0,~scanf("%998[^\n]",l)){getchar();l[strcspn(l,"#")]=0;for(p=l
,k=0,d=(void*)(sph+n);k<12&&sscanf(p,"%lf%n",d+k,&c)>0;p+=c)k++;n+=n<98&&k>11&&
sscanf(p,"%*s")<0;}printf("P3\n64 48\n255\n");for(;yx<64*48;yx++){for(A=O,k=512;
k--;)U.x=yx%64-32+R(),U.z=24-yx/64-R(),U.y=64,A=vcomb(1./512,trace(O,vunit(U)),A
);printf("%.0f %.0f %.0f\n",q(A.x),q(A.y),q(A.z));}}
